// Assets: the list (a page at a time), an upload (PUT /v1/assets/NAME with
// the file as the body) and each asset's description.
import * as api from './api.js';
import { clear, el, errorBox, hashQuery, num, valueTable, when } from './util.js';

export async function renderList(main) {
  const q = hashQuery();
  const url = `/v1/assets?limit=100${q.get('cursor') ? `&cursor=${encodeURIComponent(q.get('cursor'))}` : ''}`;
  const file = el('input', { type: 'file', name: 'file', accept: '.glb,.gltf,.hdr,.exr', required: true });
  const name = el('input', { name: 'name', size: 28, placeholder: 'name (the file\'s by default)' });
  const note = el('p.upload-note');
  const form = el('form.filters#upload-form', el('b', 'Upload '), file, ' as ', name,
    el('button', { type: 'submit' }, 'Upload'), note);
  file.onchange = () => {
    if (!name.value && file.files[0])
      name.value = file.files[0].name;
  };
  form.onsubmit = async (ev) => {
    ev.preventDefault();
    const f = file.files[0];
    const n = (name.value || (f && f.name) || '').trim();
    if (!f || !n)
      return;
    note.textContent = `Uploading ${n} (${num(f.size)} bytes) and converting it…`;
    try {
      const { status } = await api.send('PUT', `/v1/assets/${encodeURIComponent(n)}`, f);
      note.textContent = `${n}: ${status === 201 ? 'stored' : 'replaced'}.`;
      location.hash = `#/asset/${encodeURIComponent(n)}`;
    } catch (err) {
      note.replaceChildren(errorBox(err));
    }
  };
  main.append(el('h1', 'Assets'), form);
  const page = await api.json(url);
  const assets = page.assets || [];
  main.append(el('table.list#asset-list',
    el('thead', el('tr', ['name', 'size', 'format', 'created', 'triangles', 'meshes', 'source', 'SHA-256'].map((h) => el('th', h)))),
    el('tbody', assets.map((a) => el('tr', { dataset: { name: a.name } },
      el('td', el('a', { href: `#/asset/${encodeURIComponent(a.name)}` }, a.name)),
      el('td.num', num(a.size)), el('td', a.format || ''), el('td', when(a.created)),
      el('td.num', num((a.summary || {}).triangles)), el('td.num', num((a.summary || {}).meshes)),
      el('td', a.read_only ? `${a.source || 'asset-dir'} (read-only)` : (a.source || 'upload')),
      el('td.mono', (a.sha256 || '').slice(0, 16)))))));
  if (!assets.length)
    main.append(el('p.muted', 'No asset yet: upload a .glb, or a .gltf with embedded buffers.'));
  if (page.next) {
    const cursor = new URL(page.next, location.origin).searchParams.get('cursor');
    main.append(el('div.pager', el('a.button', { href: `#/assets?cursor=${encodeURIComponent(cursor)}` }, 'More →')));
  }
}

export async function render(main, name) {
  const a = await api.json(`/v1/assets/${encodeURIComponent(name)}`);
  const del = a.read_only ? null : el('button', { type: 'button' }, 'Delete');
  const msg = el('span');
  if (del)
    del.onclick = async () => {
      if (!confirm(`Delete the asset ${name}?`))
        return;
      try {
        await api.send('DELETE', `/v1/assets/${encodeURIComponent(name)}`);
        location.hash = '#/assets';
      } catch (err) {
        clear(msg).append(errorBox(err));
      }
    };
  // Its fidelity against the Khronos glTF Sample Viewer, where the daemon
  // has the reference (POST /v1/assets/NAME/fidelity: a job).
  const info = await api.info().catch(() => ({}));
  const ref = info.reference || {};
  const fidelity = el('section.fidelity-form', el('h2', 'Fidelity against the Khronos glTF Sample Viewer'));
  if (ref.available) {
    const form = el('form.filters#fidelity-form',
      el('label', 'size ', el('input', { name: 'width', type: 'number', value: 320, min: 16, max: 4096, size: 5 }),
        ' × ', el('input', { name: 'height', type: 'number', value: 240, min: 16, max: 4096, size: 5 })),
      el('label', 'channels ', el('select', { name: 'channels' },
        el('option', { value: 'all' }, 'all'), el('option', { value: 'lit' }, 'the lit image only'))),
      el('button', { type: 'submit' }, 'Compare'));
    const note = el('span');
    form.onsubmit = async (ev) => {
      ev.preventDefault();
      const body = { width: Number(form.width.value), height: Number(form.height.value) };
      if (form.channels.value !== 'all')
        body.channels = ['lit'];
      try {
        const { body: job } = await api.send('POST', `/v1/assets/${encodeURIComponent(name)}/fidelity`, body);
        location.hash = `#/job/${job.id}`;
      } catch (err) {
        clear(note).append(errorBox(err));
      }
    };
    fidelity.append(el('p.muted', `${ref.viewer || 'the viewer'} in headless Chromium draws the asset with the same camera, ` +
      'lights and look, lit and in its debug channels; the job compares each with shadebench\'s ' +
      '(its page shows them in the image comparison).'), form, note);
  } else {
    fidelity.append(el('p.muted', `This daemon has no reference renderer${ref.missing ? `: ${ref.missing}` : ''}.`));
  }
  main.append(el('h1', `Asset ${a.name}`),
    el('p', `${num(a.size)} bytes, ${a.format || ''}, SHA-256 `, el('code', a.sha256 || ''), ' ', del, msg),
    el('p', 'Render it: ', el('code', `curl -d '{"technique":"forward","scene":{"asset":"${a.name}"}}' $S/v1/jobs`),
      ' · ', el('a', { href: `#/jobs?technique=&labels=` }, 'jobs')),
    el('h2', 'What the converter found'), valueTable(a.description || {}), fidelity);
}
