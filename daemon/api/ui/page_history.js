// placeholder, replaced below
export async function render(main) { main.append('History'); }
