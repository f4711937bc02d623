// The reference render, inside headless Chromium: the Khronos glTF Sample
// Viewer (@khronosgroup/gltf-viewer, served as viewer/gltf-viewer.module.js)
// draws the job's asset with the job's camera (its resolved view and
// projection matrices), lights (KHR_lights_punctual, the daemon's list in
// glTF units), environment, exposure and tone curve, once lit and once per
// debug channel, and hands back each image as RGBA rows (bottom row first,
// as gl.readPixels reads them). shadebench-reference (reference_main.c)
// serves every file this page asks for and calls sbRender(request) over the
// DevTools protocol; nothing is fetched from anywhere else.
import { GltfView, GltfState, ResourceLoader } from "./viewer/gltf-viewer.module.js";

// The viewer's debug outputs by shadebench's look.debug names.
const DEBUG = {
    lit: GltfState.DebugOutput.NONE,
    shading_normal: GltfState.DebugOutput.generic.WORLDSPACENORMAL,
    geometric_normal: GltfState.DebugOutput.generic.GEOMETRYNORMAL,
    normal_texture: GltfState.DebugOutput.generic.NORMAL,
    tangent: GltfState.DebugOutput.generic.TANGENT,
    bitangent: GltfState.DebugOutput.generic.BITANGENT,
    base_color: GltfState.DebugOutput.mr.BASECOLOR,
    metallic: GltfState.DebugOutput.mr.METALLIC,
    roughness: GltfState.DebugOutput.mr.ROUGHNESS,
    occlusion: GltfState.DebugOutput.generic.OCCLUSION,
    emissive: GltfState.DebugOutput.generic.EMISSIVE,
    uv0: GltfState.DebugOutput.generic.UV_COORDS_0,
    uv1: GltfState.DebugOutput.generic.UV_COORDS_1,
    alpha: GltfState.DebugOutput.generic.ALPHA,
};
const TONEMAP = {
    pbr_neutral: GltfState.ToneMaps.KHR_PBR_NEUTRAL,
    aces: GltfState.ToneMaps.ACES_NARKOWICZ,
    none: GltfState.ToneMaps.NONE,
};
// The sheen E table the viewer fetches from its own site (not in the npm
// package): one white texel; only KHR_materials_sheen reads it, which
// shadebench does not render.
const SHEEN_E = "data:image/png;base64,iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAAC0lEQVR4AWP4DwQACfsD/c8LaHIAAAAASUVORK5CYII=";

function glbSplit(buf) {
    const dv = new DataView(buf);
    if (dv.getUint32(0, true) !== 0x46546C67)
        throw new Error("the asset is not a binary glTF");
    let json, bin, pos = 12;
    while (pos + 8 <= buf.byteLength) {
        const len = dv.getUint32(pos, true), type = dv.getUint32(pos + 4, true);
        const body = buf.slice(pos + 8, pos + 8 + len);
        if (type === 0x4E4F534A) json = JSON.parse(new TextDecoder().decode(body));
        else if (type === 0x004E4942) bin = body;
        pos += 8 + len;
    }
    return { json, bin };
}

function glbJoin(json, bin) {
    let text = new TextEncoder().encode(JSON.stringify(json));
    const jlen = (text.length + 3) & ~3, blen = bin ? (bin.byteLength + 3) & ~3 : 0;
    const total = 12 + 8 + jlen + (bin ? 8 + blen : 0);
    const out = new Uint8Array(total), dv = new DataView(out.buffer);
    dv.setUint32(0, 0x46546C67, true); dv.setUint32(4, 2, true); dv.setUint32(8, total, true);
    dv.setUint32(12, jlen, true); dv.setUint32(16, 0x4E4F534A, true);
    out.fill(0x20, 20, 20 + jlen); out.set(text, 20);
    if (bin) {
        dv.setUint32(20 + jlen, blen, true); dv.setUint32(24 + jlen, 0x004E4942, true);
        out.set(new Uint8Array(bin), 28 + jlen);
    }
    return out.buffer;
}

// A node whose -z axis is dir (a light shines down its node's -z), at pos.
function lightMatrix(pos, dir) {
    const n = (v) => { const l = Math.hypot(v[0], v[1], v[2]) || 1; return [v[0] / l, v[1] / l, v[2] / l]; };
    const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
    const z = n([-dir[0], -dir[1], -dir[2]]);
    const up = Math.abs(z[1]) > 0.99 ? [1, 0, 0] : [0, 1, 0];
    const x = n(cross(up, z)), y = cross(z, x);
    return [x[0], x[1], x[2], 0, y[0], y[1], y[2], 0, z[0], z[1], z[2], 0, pos[0], pos[1], pos[2], 1];
}

// The job's lights replace the file's: the daemon's list (result.scene.gltf_lights)
// is what it drew, in glTF's units.
function setLights(json, lights) {
    for (const node of json.nodes || [])
        if (node.extensions) delete node.extensions.KHR_lights_punctual;
    if (json.extensions) delete json.extensions.KHR_lights_punctual;
    if (!lights.length) return;
    json.extensionsUsed = (json.extensionsUsed || []).filter((e) => e !== "KHR_lights_punctual");
    json.extensionsUsed.push("KHR_lights_punctual");
    json.extensions = json.extensions || {};
    const list = [];
    json.nodes = json.nodes || [];
    const scene = json.scenes[json.scene === undefined ? 0 : json.scene];
    lights.forEach((l, i) => {
        const light = { type: l.type, color: l.color, intensity: l.intensity };
        if (l.range) light.range = l.range;
        if (l.type === "spot")
            light.spot = { innerConeAngle: l.inner_cone_deg * Math.PI / 180,
                           outerConeAngle: l.outer_cone_deg * Math.PI / 180 };
        list.push(light);
        json.nodes.push({ name: "shadebench light " + i,
                          matrix: lightMatrix(l.position || [0, 0, 0], l.direction || [0, 0, -1]),
                          extensions: { KHR_lights_punctual: { light: i } } });
        scene.nodes.push(json.nodes.length - 1);
    });
    json.extensions.KHR_lights_punctual = { lights: list };
}

// The viewer reads a node's matrix as translation, rotation and scale
// (gltfNode.applyMatrix: gl-matrix's getScaling, the columns' lengths, then
// getRotation of what is left), so a matrix whose determinant is negative,
// a mirror, loses its reflection: the scale comes back positive and the
// rotation is read from an improper matrix (KhronosGroup/glTF-Sample-Viewer
// issue 351). glTF says such a matrix MUST be decomposable into TRS: a
// negative scale. So each mirrored matrix is handed to the viewer as the
// same transform spelt as translation, rotation and a scale whose x is
// negative (the product is the matrix; which axis carries the sign does not
// change it). Returns the indices of the nodes restated.
function restateMirroredMatrices(json) {
    const restated = [];
    (json.nodes || []).forEach((node, i) => {
        const m = node.matrix;
        if (!m || m.length !== 16 || m[3] !== 0 || m[7] !== 0 || m[11] !== 0 || m[15] !== 1)
            return;
        const c = [[m[0], m[1], m[2]], [m[4], m[5], m[6]], [m[8], m[9], m[10]]];
        const det = c[0][0] * (c[1][1] * c[2][2] - c[1][2] * c[2][1])
                  - c[1][0] * (c[0][1] * c[2][2] - c[0][2] * c[2][1])
                  + c[2][0] * (c[0][1] * c[1][2] - c[0][2] * c[1][1]);
        if (!(det < 0)) return;
        const s = c.map((col) => Math.hypot(col[0], col[1], col[2]));
        if (!(s[0] > 0 && s[1] > 0 && s[2] > 0)) return;
        s[0] = -s[0];
        // r[row][col], a proper rotation.
        const r = [0, 1, 2].map((row) => [0, 1, 2].map((col) => c[col][row] / s[col]));
        const tr = r[0][0] + r[1][1] + r[2][2];
        let q;
        if (tr > 0) {
            const k = 0.5 / Math.sqrt(tr + 1);
            q = [(r[2][1] - r[1][2]) * k, (r[0][2] - r[2][0]) * k, (r[1][0] - r[0][1]) * k, 0.25 / k];
        } else if (r[0][0] > r[1][1] && r[0][0] > r[2][2]) {
            const k = 2 * Math.sqrt(1 + r[0][0] - r[1][1] - r[2][2]);
            q = [0.25 * k, (r[0][1] + r[1][0]) / k, (r[0][2] + r[2][0]) / k, (r[2][1] - r[1][2]) / k];
        } else if (r[1][1] > r[2][2]) {
            const k = 2 * Math.sqrt(1 + r[1][1] - r[0][0] - r[2][2]);
            q = [(r[0][1] + r[1][0]) / k, 0.25 * k, (r[1][2] + r[2][1]) / k, (r[0][2] - r[2][0]) / k];
        } else {
            const k = 2 * Math.sqrt(1 + r[2][2] - r[0][0] - r[1][1]);
            q = [(r[0][2] + r[2][0]) / k, (r[1][2] + r[2][1]) / k, 0.25 * k, (r[1][0] - r[0][1]) / k];
        }
        const ql = Math.hypot(q[0], q[1], q[2], q[3]);
        delete node.matrix;
        node.translation = [m[12], m[13], m[14]];
        node.rotation = q.map((v) => v / ql);
        node.scale = s;
        restated.push(i);
    });
    return restated;
}

// The viewer's world bitangent (its vertex shader, 1.1.0), and the same
// turned by the model matrix's handedness (sbRender's shaderSource).
const BITANGENT_W = "vec3 bitangentW=cross(normalW,tangentW)*a_tangent.w;";
const BITANGENT_W_MIRRORED = "vec3 bitangentW=cross(normalW,tangentW)*a_tangent.w" +
    "*(determinant(mat3(u_ModelMatrix))<0.0?-1.0:1.0);";

// A Radiance picture of constant radiance 1 (RGBE 128,128,128,129), for a
// uniform environment: the viewer needs one even to light with none.
function uniformHdr() {
    const w = 64, h = 32, head = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y " + h + " +X " + w + "\n";
    const out = new Uint8Array(head.length + w * h * 4);
    for (let i = 0; i < head.length; i++) out[i] = head.charCodeAt(i);
    for (let i = head.length; i < out.length; i += 4) { out[i] = out[i + 1] = out[i + 2] = 128; out[i + 3] = 129; }
    return out.buffer;
}

function base64(bytes) {
    let s = "";
    for (let i = 0; i < bytes.length; i += 0x8000)
        s += String.fromCharCode.apply(null, bytes.subarray(i, i + 0x8000));
    return btoa(s);
}

window.sbRender = async function (req) {
    const t0 = performance.now();
    const canvas = document.getElementById("view");
    canvas.width = req.width;
    canvas.height = req.height;
    const gl = canvas.getContext("webgl2", { antialias: false, alpha: false, depth: true,
                                             preserveDrawingBuffer: true, powerPreference: "default" });
    if (!gl) throw new Error("no WebGL 2 context");
    // No anisotropic filtering: the viewer asks for 16x on every mipmapped
    // texture, shadebench never (its sample pattern is each driver's own),
    // and textures seen at an angle would differ by the filter alone.
    // Each change made to the viewer is listed in the answer (viewer_patches).
    const patches = [];
    const getExtension = gl.getExtension.bind(gl);
    gl.getExtension = (name) => {
        if (name !== "EXT_texture_filter_anisotropic") return getExtension(name);
        if (!patches.includes("no_anisotropic_filtering")) patches.push("no_anisotropic_filtering");
        return null;
    };
    // The tangent frame of a mirrored node. glTF states the bitangent of
    // the mesh's own attributes, cross(normal, tangent.xyz) * tangent.w,
    // a direction in the mesh's space that the node's matrix M carries
    // like the tangent: M * B. The viewer's vertex shader takes the cross
    // of the normal and tangent already in world space, which under a
    // mirror (det M < 0) is -M * B: the normal map's green channel turned
    // over, unlike the same mesh with the node baked into its vertices
    // (MikkTSpace's handedness turns with the mirrored UV layout; the
    // viewer draws that one as M * B). So the world cross is multiplied by
    // the sign of the model matrix's determinant, as shadebench's
    // converter turns w (convert_build.c).
    const shaderSource = gl.shaderSource.bind(gl);
    gl.shaderSource = (shader, src) => {
        if (src.includes(BITANGENT_W)) {
            src = src.replace(BITANGENT_W, BITANGENT_W_MIRRORED);
            if (!patches.includes("mirrored_bitangent")) patches.push("mirrored_bitangent");
        }
        shaderSource(shader, src);
    };
    const view = new GltfView(gl);
    const state = view.createState();
    const loader = new ResourceLoader(view, "./viewer/libs/");
    const file = await (await fetch(req.asset)).arrayBuffer();
    const parts = req.asset.endsWith(".gltf")
        ? { json: JSON.parse(new TextDecoder().decode(file)), bin: undefined } : glbSplit(file);
    setLights(parts.json, req.lights);
    const restated = restateMirroredMatrices(parts.json);
    state.gltf = await loader.loadGltf(glbJoin(parts.json, parts.bin));
    state.sceneIndex = state.gltf.scene === undefined ? 0 : state.gltf.scene;
    gl.finish();
    const t1 = performance.now();
    const envFile = req.environment_url ? await (await fetch(req.environment_url)).arrayBuffer() : uniformHdr();
    state.environment = await loader.loadEnvironment(envFile, { lut_sheen_E_file: SHEEN_E });
    const px1 = new Uint8Array(4);
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px1); // waits for the filtering
    const t2 = performance.now();

    // The camera: the job's matrices, as they are.
    state.cameraIndex = undefined;
    const cam = state.userCamera;
    cam.getViewMatrix = () => new Float32Array(req.view);
    cam.getProjectionMatrix = () => new Float32Array(req.projection);
    cam.getPosition = () => new Float32Array(req.eye);
    const p = state.renderingParameters;
    p.usePunctual = true;
    p.useIBL = true;
    p.iblIntensity = req.ibl_intensity;
    p.environmentRotation = req.environment_rotation_deg;
    p.blurEnvironmentMap = false;
    p.useDirectionalLightsWithDisabledIBL = false;
    p.exposure = req.exposure;
    p.toneMap = TONEMAP[req.tonemap];
    p.clearColor = req.clear;
    p.internalMSAA = 1;
    const out = [];
    for (const name of req.channels) {
        if (!(name in DEBUG)) throw new Error("no such channel " + name);
        p.debugOutput = DEBUG[name];
        // shadebench draws an uploaded environment behind the lit image and
        // black behind a debug channel.
        p.renderEnvironmentMap = name === "lit" && !!req.render_environment;
        const c0 = performance.now();
        view.renderFrame(state, req.width, req.height);
        const px = new Uint8Array(req.width * req.height * 4);
        gl.readPixels(0, 0, req.width, req.height, gl.RGBA, gl.UNSIGNED_BYTE, px);
        out.push({ name, render_ms: performance.now() - c0, rgba: base64(px) });
    }
    return { load_ms: t1 - t0, environment_ms: t2 - t1, channels: out,
             mirrored_matrices_restated: restated, viewer_patches: patches,
             subpixel_bits: gl.getParameter(gl.SUBPIXEL_BITS),
             renderer: gl.getParameter(gl.RENDERER), version: gl.getParameter(gl.VERSION) };
};
window.sbReady = true;
