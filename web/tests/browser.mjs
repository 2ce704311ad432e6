// End-to-end tests of the editor page in headless Chromium (Debian's `chromium`), driven by
// playwright-core. Needs a running `snowscape serve`; SNOWSCAPE_URL says where.
// Checks: the page draws a non-blank terrain, a brush stroke raises the snow depth where it
// was applied (read back from the server), a triggered avalanche moves snow downhill, the
// timeline steps a day, a second tab sees the same state, malformed messages get error
// replies without breaking the session, requests from other origins or with other Host
// names are refused, a long step runs on a worker (another tab is answered meanwhile) and
// the cancel button stops it, a hover readout that matches the server's cell, Ctrl+Z / Ctrl+Y undo and redo, the home and top views and a camera
// that a step keeps, the parameter panel (help, ranges and choices from the server, a
// confirmation before the restart), and (with SNOWSCAPE_TOKEN_URL, a server bound to 0.0.0.0) the
// page needs its access token and then runs on the cookie; the view is lit by the season's sun
// with shadows and haze, snow brighter and bluer than bare ground; a DEM imported from the page
// becomes the terrain and a bad one is refused. Writes screenshots to
// SNOWSCAPE_SHOTS (default /tmp).
import { launchChromium, steepestCellInPage } from './common.mjs';
import assert from 'node:assert/strict';
import http from 'node:http';

const url = process.env.SNOWSCAPE_URL;
if (!url) { console.error('SNOWSCAPE_URL is not set'); process.exit(2); }
const shots = process.env.SNOWSCAPE_SHOTS || '/tmp';
// The printed URL carries the server's access token (?token=): the page keeps it in its
// cookie; this script's own requests send it in the X-Snowscape-Token header.
const base = new URL(url).origin;
const token = new URL(url).searchParams.get('token') || '';
const auth = { 'X-Snowscape-Token': token };
const nodeFetch = globalThis.fetch;
const fetch = (u, o = {}) => nodeFetch(u, { ...o, headers: { ...auth, ...(o.headers || {}) } });
const cell = async (c, r) => (await fetch(`${base}/api/cell?col=${c}&row=${r}`)).json();
const results = [];
async function check(name, fn) {
  const t = Date.now();
  try { await fn(); results.push([name, 'ok', Date.now() - t]); console.log(`ok   ${name} (${Date.now() - t} ms)`); }
  catch (e) { results.push([name, 'FAILED', e]); console.log(`FAIL ${name}: ${e.stack || e}`); }
}

const browser = await launchChromium();
const context = await browser.newContext({ viewport: { width: 1200, height: 800 } });
const page = await context.newPage();
page.on('pageerror', (e) => console.log('page error:', e.message));

// Canvas statistics read back from WebGL (preserveDrawingBuffer): distinct colours and spread.
const canvasStats = () => page.evaluate(() => {
  const src = document.querySelector('#view canvas');
  const c = document.createElement('canvas');
  c.width = 200; c.height = 150;
  const g = c.getContext('2d');
  g.drawImage(src, 0, 0, 200, 150);
  const d = g.getImageData(0, 0, 200, 150).data;
  const colours = new Set();
  let white = 0;
  for (let i = 0; i < d.length; i += 4) {
    colours.add((d[i] >> 3) << 10 | (d[i + 1] >> 3) << 5 | (d[i + 2] >> 3));
    if (d[i] > 220 && d[i + 1] > 220 && d[i + 2] > 220) white++;
  }
  return { colours: colours.size, white };
});

await check('page loads and draws a non-blank terrain', async () => {
  const t0 = Date.now();
  await page.goto(url);
  await page.waitForFunction(() => window.snowscape && window.snowscape.state && window.snowscape.frames >= 10, null, { timeout: 60000 });
  await page.waitForTimeout(1500);
  console.log(`     page load to first full state: ${Date.now() - t0} ms`);
  await page.screenshot({ path: `${shots}/editor_start.png` });
  const s = await canvasStats();
  assert.ok(s.colours > 50, `only ${s.colours} colours on the canvas`);
});

let brushCell;
await check('a brush stroke raises the snow depth where it was applied (server state)', async () => {
  await page.selectOption('#tool', 'brush');
  await page.selectOption('#op', 'add');
  await page.selectOption('#target', 'all');
  await page.fill('#strength', '1.5');
  await page.fill('#radius', '200');
  const box = await page.locator('#view canvas').boundingBox();
  const x = box.x + box.width / 2, y = box.y + box.height / 2;
  brushCell = await page.evaluate(([x, y]) => window.snowscape.pickAt(x, y), [x, y]);
  assert.ok(brushCell, 'the view centre hits the terrain');
  const c = Math.round(brushCell.col), r = Math.round(brushCell.row);
  const before = (await cell(c, r)).depth;
  await page.mouse.move(x, y);
  await page.mouse.down();
  await page.mouse.move(x + 3, y + 2, { steps: 3 });
  await page.mouse.up();
  let after = before;
  for (let k = 0; k < 50 && after <= before + 1; k++) { await page.waitForTimeout(100); after = (await cell(c, r)).depth; }
  assert.ok(after > before + 1, `depth at (${c}, ${r}) went ${before} -> ${after}`);
  await page.waitForTimeout(500);
  await page.screenshot({ path: `${shots}/editor_brush.png` });
});

await check('hovering shows the cell under the cursor (as the server has it) and the brush ring', async () => {
  await page.selectOption('#tool', 'brush');
  const box = await page.locator('#view canvas').boundingBox();
  const x = box.x + box.width * 0.4, y = box.y + box.height * 0.55;
  await page.mouse.move(x, y);
  await page.mouse.move(x + 2, y + 1);
  await page.waitForFunction(() => window.snowscape.hover, null, { timeout: 5000 });
  const h = await page.evaluate(() => window.snowscape.hover);
  const srv = await cell(h.col, h.row);
  assert.ok(Math.abs(h.altitude - srv.bedrock) < 0.5, `readout ${h.altitude} m, server ${srv.bedrock} m`);
  assert.ok(Math.abs(h.depth - srv.depth) < 0.01, `readout depth ${h.depth} m, server ${srv.depth} m`);
  assert.ok(h.slope >= 0 && h.slope < 90 && h.aspect >= 0 && h.aspect < 360, JSON.stringify(h));
  const text = await page.locator('#readout').textContent();
  assert.match(text, /slope \d+° · faces [NESW]+/);
  await page.screenshot({ path: `${shots}/editor_hover.png` });
});

await check('a second tab sees the same state', async () => {
  const p2 = await context.newPage();
  await p2.goto(url);
  await p2.waitForFunction(() => window.snowscape && window.snowscape.state && window.snowscape.frames >= 10, null, { timeout: 60000 });
  const [a, b] = await Promise.all([page, p2].map((p) => p.evaluate(() => {
    const s = window.snowscape.state;
    const g = window.snowscape.grids;
    let d = 0;
    for (const l of ['compacted', 'stable', 'unstable', 'powder']) for (let i = 0; i < g[l].length; i++) d += g[l][i];
    return { undo: s.undo, day: s.day, depthSum: Math.round(d) };
  })));
  assert.deepEqual(a, b);
  assert.equal(a.undo, 1);
  await p2.close();
});

await check('Ctrl+Z undoes the stroke, Ctrl+Y redoes it; H and T set the view, which a step keeps', async () => {
  await page.evaluate(() => document.activeElement && document.activeElement.blur());
  const undo = () => page.evaluate(() => [window.snowscape.state.undo, window.snowscape.state.redo]);
  assert.deepEqual(await undo(), [1, 0]);
  await page.keyboard.press('Control+z');
  await page.waitForFunction(() => window.snowscape.state.undo === 0, null, { timeout: 10000 });
  assert.deepEqual(await undo(), [0, 1]);
  await page.keyboard.press('Control+y');
  await page.waitForFunction(() => window.snowscape.state.undo === 1, null, { timeout: 10000 });
  const home = await page.evaluate(() => window.snowscape.cameraPosition());
  await page.keyboard.press('t');
  const top = await page.evaluate(() => window.snowscape.cameraPosition());
  assert.notDeepEqual(top, home, 'the top view moves the camera');
  assert.ok(top[1] > home[1], 'the top view looks from higher up');
  await page.screenshot({ path: `${shots}/editor_top_view.png` });
  await page.keyboard.press('h');
  assert.deepEqual(await page.evaluate(() => window.snowscape.cameraPosition()), home);
});

await check('a triggered avalanche moves snow downhill', async () => {
  // The steepest cell of the bedrock, loaded with unstable snow through brush messages.
  const site = await steepestCellInPage(page);
  await page.evaluate((p) => window.snowscape.send({ type: 'brush', stroke: 9000, op: 'add', target: 'unstable', col: p.col, row: p.row, radius_m: 150, strength: 2, value: 0 }), site);
  await page.waitForTimeout(500);
  const meanAlt = () => page.evaluate(() => {
    const g = window.snowscape.grids;
    let a = 0, m = 0;
    for (let i = 0; i < g.bedrock.length; i++) {
      const d = g.compacted[i] + g.stable[i] + g.unstable[i] + g.powder[i];
      a += d * g.bedrock[i]; m += d;
    }
    return a / m;
  });
  const before = await meanAlt();
  await page.selectOption('#tool', 'avalanche');
  await page.evaluate((p) => window.snowscape.send({ type: 'trigger_avalanche', col: p.col, row: p.row }), site);
  await page.waitForFunction(() => window.snowscape.lastAvalanche && window.snowscape.lastAvalanche.phase === 'running', null, { timeout: 20000 });
  await page.screenshot({ path: `${shots}/editor_avalanche.png` });
  await page.waitForFunction(() => window.snowscape.lastAvalanche && window.snowscape.lastAvalanche.phase === 'ended', null, { timeout: 120000 });
  await page.waitForTimeout(500);
  const after = await meanAlt();
  const av = await page.evaluate(() => window.snowscape.lastAvalanche);
  assert.ok(av.records > 5, `${av.records} flow frames`);
  assert.ok(after < before - 0.5, `snow mean altitude ${before} -> ${after}`);
  assert.ok(Number.isFinite(av.entrained_m3) && av.entrained_m3 >= 0, `entrained ${av.entrained_m3}`);
  assert.match(await page.textContent('#status'), /m³ entrained/);
  console.log(`     avalanche: ${av.records} frames, ${av.released_m3.toFixed(0)} m³ released, ${av.entrained_m3.toFixed(0)} m³ entrained, ${av.time_s.toFixed(1)} s simulated`);
});

await check('the timeline steps a day', async () => {
  const d0 = await page.evaluate(() => window.snowscape.state.day);
  await page.keyboard.press('t');
  const view = await page.evaluate(() => window.snowscape.cameraPosition());
  await page.click('#step');
  await page.waitForFunction((d0) => window.snowscape.state.day >= d0 + 0.99, d0, { timeout: 120000 });
  await page.waitForTimeout(500);
  assert.deepEqual(await page.evaluate(() => window.snowscape.cameraPosition()), view, 'the step kept the camera');
  await page.keyboard.press('h');
  const s = await page.evaluate(() => window.snowscape.state);
  assert.equal(s.snapshots.length, 2);
  const srv = await (await fetch(`${base}/api/state`)).json();
  assert.equal(srv.day, s.day);
  await page.screenshot({ path: `${shots}/editor_day1.png` });
});

await check('every shading has a legend with its unit and fixed range; the wind has arrows', async () => {
  const legendOf = async (mode) => {
    await page.selectOption('#shade', mode);
    await page.waitForTimeout(200);
    return page.evaluate(() => ({ text: document.getElementById('legend').textContent, arrows: window.snowscape.windArrows }));
  };
  const t = await legendOf('temperature');
  assert.match(t.text, /air temperature, °C/); assert.match(t.text, /-20/); assert.match(t.text, /15/);
  assert.equal(t.arrows, 0);
  const w = await legendOf('wind');
  assert.match(w.text, /wind speed.*m\/s/); assert.match(w.text, /20/);
  assert.ok(w.arrows > 20, `${w.arrows} wind arrows`);
  await page.screenshot({ path: `${shots}/editor_wind_legend.png` });
  assert.match((await legendOf('sun')).text, /direct sun, h\/day/);
  assert.match((await legendOf('stability')).text, /unstable snow or powder on top/);
  assert.match((await legendOf('layers')).text, /compacted.*stable.*unstable.*powder/);
  const d = await legendOf('depth');
  assert.match(d.text, /snow depth, m/); assert.equal(d.arrows, 0);
  // A second tab shows the same legend for the same mode (fixed ranges).
  const other = await context.newPage();
  await other.goto(url);
  await other.waitForFunction(() => window.snowscape && window.snowscape.state, null, { timeout: 60000 });
  await other.selectOption('#shade', 'depth');
  assert.equal(await other.evaluate(() => document.getElementById('legend').textContent), d.text);
  await other.close();
});

await check('the parameter panel: sections with help, ranges and choices from the server; apply asks first', async () => {
  await page.click('#params-box > summary');
  const sel = '#params [data-path="slope_shedding.min_slope_deg"]';
  await page.waitForSelector(sel, { state: 'attached', timeout: 20000 });
  await page.click('#params details.section:has(> summary:text-is("slope_shedding")) > summary');
  await page.waitForSelector(sel, { timeout: 5000 });
  const f = await page.evaluate((sel) => {
    const inp = document.querySelector(sel);
    return { min: inp.min, max: inp.max, help: inp.parentElement.querySelector('.help').textContent,
      title: inp.parentElement.title, sections: document.querySelectorAll('#params details.section').length,
      law: [...document.querySelector('#params [data-path="slope_shedding.law"]').options].map((o) => o.value) };
  }, sel);
  assert.equal(f.min, '0'); assert.equal(f.max, '90');
  assert.match(f.help, /^Slope below which a cell does not shed its own snow.*\[0, 90\]$/);
  assert.match(f.title, /FSM2oshd/);
  assert.ok(f.sections >= 10, `${f.sections} sections`);
  assert.deepEqual(f.law, ['exponential', 'power_law']);
  // Dismissing the confirmation changes nothing; accepting restarts with the new value.
  const day = await page.evaluate(() => window.snowscape.state.day);
  await page.fill(sel, '55');
  page.once('dialog', (d) => d.dismiss());
  await page.click('#params-apply');
  await page.waitForTimeout(500);
  assert.equal(await page.evaluate(() => window.snowscape.state.day), day);
  page.once('dialog', (d) => d.accept());
  await page.click('#params-apply');
  await page.waitForFunction(() => window.snowscape.state.scenario.parameters.slope_shedding.min_slope_deg === 55, null, { timeout: 60000 });
  assert.equal(await page.evaluate(() => window.snowscape.state.day), 0);
  await page.screenshot({ path: `${shots}/editor_parameters.png` });
});

await check('the weather table has a column per field of the Rust weather period; an empty optional field is sent as its default', async () => {
  const proto = await (await fetch(`${base}/api/protocol`)).json();
  const heads = await page.$$eval('#weather-head th', (ths) => ths.map((t) => t.textContent));
  assert.deepEqual(heads.slice(0, -1), proto.weather_fields.map((f) => `${f.label}${f.unit}`));
  assert.ok(heads.includes('precip.mm/day'), heads.join(' | '));
  const rows = await page.$$eval('#weather tbody tr', (trs) => trs.map((tr) => tr.querySelectorAll('input').length));
  assert.ok(rows.length >= 1 && rows.every((n) => n === proto.weather_fields.length), `${rows}`);
  // Add a period, set its precipitation, apply: the scenario holds it; the others stay default.
  await page.click('#weather-add');
  const last = '#weather tbody tr:last-child input';
  const n = proto.weather_fields.findIndex((f) => f.name === 'precipitation_mm_per_day');
  await page.locator(last).nth(n).fill('4.5');
  await page.locator(last).nth(n).dispatchEvent('change');
  page.once('dialog', (d) => d.accept());
  await page.click('#weather-apply');
  await page.waitForFunction(() => {
    const w = window.snowscape.state.scenario.weather;
    return w.length >= 2 && w[w.length - 1].precipitation_mm_per_day === 4.5;
  }, null, { timeout: 60000 });
  const w = await page.evaluate(() => window.snowscape.state.scenario.weather);
  assert.ok(w.slice(0, -1).every((p) => p.precipitation_mm_per_day === undefined || p.precipitation_mm_per_day === null), JSON.stringify(w));
  await page.locator('#weather').screenshot({ path: `${shots}/editor_weather.png` });
});

await check('a long step runs on a worker: another tab is answered meanwhile, and cancel stops it', async () => {
  // A season long and busy enough that the step cannot end before the test cancels it on
  // any machine (a 99-day step of the default season took under a second).
  const original = await page.evaluate(() => structuredClone(window.snowscape.state.scenario));
  const heavy = structuredClone(original);
  heavy.days = 3650;
  heavy.events.melt_and_state = 100;
  heavy.events.wind_transport = 100;
  const setScenario = async (sc) => {
    await page.evaluate((sc) => window.snowscape.send({ type: 'set_scenario', scenario: sc }), sc);
    await page.waitForFunction((days) => window.snowscape.state.season_days === days && !window.snowscape.state.busy, sc.days, { timeout: 120000 });
  };
  await setScenario(heavy);
  const d0 = await page.evaluate(() => window.snowscape.state.day);
  const p2 = await context.newPage();
  await p2.goto(url);
  await p2.waitForFunction(() => window.snowscape && window.snowscape.state && window.snowscape.frames >= 10, null, { timeout: 60000 });
  const prev = await page.evaluate(() => (window.snowscape.lastJob || { id: 0 }).id);
  await page.evaluate(() => window.snowscape.send({ type: 'step', days: 365 }));
  await page.waitForFunction((prev) => { const j = window.snowscape.lastJob; return j && j.id > prev; }, prev, { timeout: 10000 });
  // The other tab's probe is answered while the step runs (its job is not over yet).
  const seen = await p2.evaluate(() => new Promise((resolve) => {
    const a = window.snowscape;
    a.lastCell = null;
    const t0 = performance.now();
    a.send({ type: 'probe', col: 10, row: 10 });
    const poll = setInterval(() => {
      if (a.lastCell) { clearInterval(poll); resolve({ phase: a.lastJob && a.lastJob.phase, ms: performance.now() - t0 }); }
    }, 2);
  }));
  assert.ok(['started', 'running'].includes(seen.phase), `the step was ${seen.phase} when the probe came back`);
  console.log(`     probe answered in ${seen.ms.toFixed(0)} ms while the step ran`);
  assert.ok(await page.isEnabled('#cancel'), 'cancel is offered while the step runs');
  await page.click('#cancel');
  await page.waitForFunction(() => ['cancelled', 'ended', 'failed'].includes(window.snowscape.lastJob.phase), null, { timeout: 120000 });
  const job = await page.evaluate(() => window.snowscape.lastJob);
  assert.equal(job.phase, 'cancelled', JSON.stringify(job));
  await page.waitForFunction(() => !window.snowscape.state.busy, null, { timeout: 10000 });
  assert.equal(await page.evaluate(() => window.snowscape.state.day), d0, 'the season stays where the step started');
  assert.ok(!(await page.isEnabled('#cancel')));
  await p2.close();
  await setScenario(original);
});

await check('malformed messages get error replies and the session goes on', async () => {
  const n0 = await page.evaluate(() => window.snowscape.errors.length);
  await page.evaluate(() => {
    const a = window.snowscape;
    a.sendRaw('not json');
    a.sendRaw('{"type":"brush","col":"x"}');
    a.sendRaw('{"type":"step","days":1e400}');
    a.sendRaw('{"type":"save","name":"../../etc"}');
    a.sendRaw(JSON.stringify({ type: 'seek', index: 1, extra: 1 }));
    a.sendRaw('x'.repeat(70000));
  });
  await page.waitForFunction((n0) => window.snowscape.errors.length >= n0 + 6, n0, { timeout: 10000 });
  const codes = await page.evaluate((n0) => window.snowscape.errors.slice(n0).map((e) => e.code), n0);
  assert.ok(codes.includes('malformed') && codes.includes('too_large') && codes.includes('invalid_value'), codes.join(','));
  await page.evaluate((c) => window.snowscape.send({ type: 'probe', col: c.col, row: c.row }), { col: Math.round(brushCell.col), row: Math.round(brushCell.row) });
  await page.waitForFunction(() => window.snowscape.lastCell, null, { timeout: 10000 });
  const open = await page.evaluate(() => window.snowscape.messages.includes('cell'));
  assert.ok(open, 'the session still answers');
});

await check('save and export from the page; exported files download; the project list, and a save over a project asks first; the screenshot button; the export as one zip', async () => {
  await page.fill('#name', 'e2e');
  await page.click('#save');
  await page.waitForFunction(() => window.snowscape.messages.includes('done'), null, { timeout: 60000 });
  const list = await (await fetch(`${base}/api/projects`)).json();
  assert.ok(list.some((p) => p.name === 'e2e' && typeof p.day === 'number'), JSON.stringify(list));
  const options = await page.evaluate(async () => { await window.snowscape.refreshProjects(); return [...document.querySelectorAll('#projects option')].map((o) => o.value); });
  assert.ok(options.includes('e2e'), options.join(', '));
  const dones = () => page.evaluate(() => window.snowscape.messages.filter((m) => m === 'done').length);
  let asked = null;
  page.once('dialog', (d) => { asked = d.message(); d.dismiss(); });
  const before = await dones();
  await page.click('#save');
  await page.waitForTimeout(800);
  assert.match(asked || '', /e2e exists: overwrite/);
  assert.equal(await dones(), before, 'a dismissed overwrite saves nothing');
  page.once('dialog', (d) => d.accept());
  await page.click('#save');
  await page.waitForFunction((n) => window.snowscape.messages.filter((m) => m === 'done').length > n, before, { timeout: 60000 });
  await page.click('#export');
  await page.waitForSelector('#files a', { timeout: 120000 });
  const links = await page.$$eval('#files a', (as) => as.map((a) => a.getAttribute('href')).filter((h) => h.startsWith('/files/')));
  for (const f of ['depth.tif', 'layers.exr', 'splat.png', 'terrain.glb', 'preview.png']) {
    assert.ok(links.some((l) => l.endsWith(`/${f}`)), `${f} missing from ${links.join(', ')}`);
  }
  // The whole export as one zip.
  const zipHref = await page.getAttribute('#export-zip', 'href');
  const zip = Buffer.from(await (await fetch(base + zipHref)).arrayBuffer());
  assert.equal(zip.subarray(0, 2).toString(), 'PK');
  for (const f of ['depth.tif', 'terrain.glb', 'preview.png']) assert.ok(zip.includes(Buffer.from(`/${f}`)), `${f} missing from the zip`);
  assert.equal((await fetch(`${base}/api/export/no_such_export`)).status, 404);
  assert.notEqual((await fetch(`${base}/api/export/..%2F..%2Fetc`)).status, 200);
  const glb = await fetch(base + links.find((l) => l.endsWith('terrain.glb')));
  assert.equal(glb.status, 200);
  assert.equal(Buffer.from(await glb.arrayBuffer()).subarray(0, 4).toString(), 'glTF');
  // The screenshot button downloads the 3D view as a PNG.
  const [download] = await Promise.all([page.waitForEvent('download'), page.click('#screenshot')]);
  assert.match(download.suggestedFilename(), /^e2e_day[0-9.]+\.png$/);
  const png = await download.path().then((p) => import('node:fs').then((fs) => fs.readFileSync(p)));
  assert.equal(png.subarray(1, 4).toString(), 'PNG');
  assert.ok(png.length > 10000, `${png.length} bytes`);
  const escape = await fetch(`${base}/files/..%2F..%2Fetc%2Fpasswd`);
  assert.notEqual(escape.status, 200);
});

// A raw HTTP request with chosen headers (fetch would fix Host itself).
const rawRequest = (path, headers) => new Promise((resolve, reject) => {
  const u = new URL(base);
  const req = http.request({ host: u.hostname, port: u.port, path, headers: { ...auth, ...headers } }, (res) => {
    res.resume();
    resolve(res.statusCode);
  });
  req.on('upgrade', (res, socket) => { socket.destroy(); resolve(res.statusCode); });
  req.on('error', reject);
  req.end();
});

await check('other sites, other local ports and rebinding names are refused (403)', async () => {
  const host = new URL(base).host;
  assert.equal(await rawRequest('/api/state', { Host: host }), 200);
  assert.equal(await rawRequest('/api/state', { Host: 'evil.example' }), 403, 'DNS rebinding Host');
  assert.equal(await rawRequest('/api/state', { Host: host, Origin: 'http://evil.example' }), 403);
  assert.equal(await rawRequest('/files/e2e/project.json', { Host: `evil.example:${new URL(base).port}` }), 403);
  const upgrade = { Host: host, Connection: 'Upgrade', Upgrade: 'websocket', 'Sec-WebSocket-Version': '13',
    'Sec-WebSocket-Key': 'dGhlIHNhbXBsZSBub25jZQ==' };
  assert.equal(await rawRequest('/ws', { ...upgrade, Origin: base }), 101, 'the page itself connects');
  assert.equal(await rawRequest('/ws', { ...upgrade, Origin: 'http://evil.example' }), 403);
  assert.equal(await rawRequest('/ws', { ...upgrade, Origin: 'http://127.0.0.1:1' }), 403, 'another local port');
  // Cross-site GETs (an <img>, a no-cors fetch: no Origin) are refused, and so is the data
  // opened from a typed URL; only the page itself opens so.
  for (const path of ['/api/state', '/api/export/e2e', '/files/e2e/project.json', '/main.js', '/']) {
    assert.equal(await rawRequest(path, { Host: host, 'Sec-Fetch-Site': 'cross-site' }), 403, path);
  }
  assert.equal(await rawRequest('/api/state', { Host: host, 'Sec-Fetch-Site': 'none' }), 403);
  assert.equal(await rawRequest('/', { Host: host, 'Sec-Fetch-Site': 'none' }), 200);
  // Without its token the data is refused, loopback included (a foreign page cannot probe it).
  assert.equal(await new Promise((resolve, reject) => {
    const u = new URL(base);
    const req = http.request({ host: u.hostname, port: u.port, path: '/api/state', headers: { Host: host } }, (res) => {
      res.resume(); resolve(res.statusCode);
    });
    req.on('error', reject);
    req.end();
  }), 403, 'no token');
  const res = await fetch(`${base}/api/state`);
  assert.equal(res.headers.get('cross-origin-resource-policy'), 'same-origin');
  assert.equal(res.headers.get('x-content-type-options'), 'nosniff');
});

await check('at most 16 tabs connect at once; a closed one frees its place', async () => {
  const u = new URL(base);
  const held = [];
  const open = () => new Promise((resolve, reject) => {
    const req = http.request({ host: u.hostname, port: u.port, path: '/ws', headers: {
      ...auth, Host: u.host, Connection: 'Upgrade', Upgrade: 'websocket', 'Sec-WebSocket-Version': '13',
      'Sec-WebSocket-Key': 'dGhlIHNhbXBsZSBub25jZQ==' } });
    req.on('upgrade', (res, socket) => { held.push(socket); resolve(res.statusCode); });
    req.on('response', (res) => { res.resume(); resolve(res.statusCode); });
    req.on('error', reject);
    req.end();
  });
  const codes = [];
  for (let k = 0; k < 20; k++) codes.push(await open());
  assert.ok(codes.filter((c) => c === 101).length <= 16, codes.join(' '));
  assert.equal(codes[codes.length - 1], 503, codes.join(' '));
  for (const sock of held) sock.destroy();
  await new Promise((r) => setTimeout(r, 500));
  assert.equal(await open(), 101, 'a place is free again');
  for (const sock of held) sock.destroy();
});

await check('a tab that asks for the whole state again and again without reading is dropped', async () => {
  const u = new URL(base);
  const payload = Buffer.from(JSON.stringify({ type: 'resync' }));
  // One masked client text frame (RFC 6455 §5.2).
  const frame = Buffer.alloc(6 + payload.length);
  frame[0] = 0x81; frame[1] = 0x80 | payload.length;
  const mask = [1, 2, 3, 4];
  mask.forEach((m, k) => { frame[2 + k] = m; });
  payload.forEach((b, k) => { frame[6 + k] = b ^ mask[k % 4]; });
  const t0 = Date.now();
  const closed = await new Promise((resolve, reject) => {
    const req = http.request({ host: u.hostname, port: u.port, path: '/ws', headers: {
      ...auth, Host: u.host, Connection: 'Upgrade', Upgrade: 'websocket', 'Sec-WebSocket-Version': '13',
      'Sec-WebSocket-Key': 'dGhlIHNhbXBsZSBub25jZQ==' } });
    req.on('upgrade', (res, socket) => {
      socket.pause(); // read nothing while the server's replies pile up
      for (let k = 0; k < 200; k++) socket.write(frame);
      // Past the server's send timeout, read what it sent: a dropped tab then sees the end.
      setTimeout(() => {
        socket.on('close', () => resolve(true));
        socket.on('error', () => resolve(true));
        socket.on('data', () => {});
        socket.resume();
        setTimeout(() => { socket.destroy(); resolve(false); }, 15000);
      }, 13000);
    });
    req.on('error', reject);
    req.end();
  });
  assert.ok(closed, 'the server kept a tab that never reads');
  console.log(`     dropped after ${Date.now() - t0} ms`);
  // The session goes on for the others.
  const st = await (await fetch(`${base}/api/state`)).json();
  assert.ok(st.width > 0);
});

await check('a real DEM with nodata (avaMal): nodata cells are not drawn and the view frames the valid cells', async () => {
  const demUrl = process.env.SNOWSCAPE_DEM_URL;
  assert.ok(demUrl, 'SNOWSCAPE_DEM_URL is not set (scripts/browser-tests.sh starts that server)');
  const p = await context.newPage();
  await p.goto(demUrl);
  await p.waitForFunction(() => window.snowscape && window.snowscape.meshTriangles > 0, null, { timeout: 120000 });
  await p.waitForTimeout(2000);
  const m = await p.evaluate(() => {
    const s = window.snowscape.state, b = window.snowscape.grids.bedrock;
    let valid = 0;
    for (let i = 0; i < b.length; i++) if (Number.isFinite(b[i])) valid++;
    return { triangles: window.snowscape.meshTriangles, quads: window.snowscape.meshQuads, valid, cells: s.width * s.height };
  });
  const share = m.triangles / 2 / m.quads;
  console.log(`     avaMal: ${(100 * m.valid / m.cells).toFixed(1)} % valid cells, ${(100 * share).toFixed(1)} % of the quads drawn`);
  assert.ok(m.valid < 0.8 * m.cells, 'avaMal has nodata');
  assert.ok(share < m.valid / m.cells + 0.02, `${share} of the quads drawn for ${m.valid / m.cells} valid cells`);
  assert.ok(share > m.valid / m.cells - 0.1, `only ${share} of the quads drawn`);
  await p.screenshot({ path: `${shots}/editor_avamal.png` });
  await p.close();
});

await check('the view looks like snow on avaMal at day 60: shadows from the season\'s sun, haze, snow brighter and bluer than bare ground', async () => {
  const demUrl = process.env.SNOWSCAPE_DEM_URL;
  assert.ok(demUrl, 'SNOWSCAPE_DEM_URL is not set (scripts/browser-tests.sh starts that server)');
  const p = await context.newPage();
  await p.goto(demUrl);
  await p.waitForFunction(() => window.snowscape && window.snowscape.meshTriangles > 0, null, { timeout: 120000 });
  await p.evaluate(() => window.snowscape.send({ type: 'step', days: 60 }));
  await p.waitForFunction(() => window.snowscape.state.day >= 60 - 1e-6 && !window.snowscape.state.busy, null, { timeout: 600000 });
  await p.evaluate(() => window.snowscape.setView('top'));
  await p.waitForTimeout(3000);
  const r = await p.evaluate(() => {
    const app = window.snowscape, s = app.state, g = app.grids;
    const rendering = app.rendering();
    // The canvas as the user sees it.
    const src = document.querySelector('#view canvas');
    const c = document.createElement('canvas');
    c.width = src.clientWidth; c.height = src.clientHeight;
    const ctx = c.getContext('2d');
    ctx.drawImage(src, 0, 0, c.width, c.height);
    const px = ctx.getImageData(0, 0, c.width, c.height).data;
    const snow = [], bare = [];
    for (let k = 0; k < s.width * s.height; k += 13) {
      if (!Number.isFinite(g.bedrock[k])) continue;
      let d = 0;
      for (const l of ['compacted', 'stable', 'unstable', 'powder']) d += g[l][k];
      const list = d >= 0.5 ? snow : d === 0 ? bare : null;
      if (!list) continue;
      const at = app.screenOf(k % s.width, Math.floor(k / s.width));
      if (!at) continue;
      const o = 4 * (Math.floor(at[1]) * c.width + Math.floor(at[0]));
      list.push([px[o], px[o + 1], px[o + 2]]);
    }
    const mean = (l, f) => l.reduce((a, v) => a + f(v), 0) / Math.max(1, l.length);
    const lum = (v) => 0.2126 * v[0] + 0.7152 * v[1] + 0.0722 * v[2];
    return {
      rendering, sun: s.sun, lat: s.latitude_deg,
      snow: snow.length, bare: bare.length,
      snowLum: mean(snow, lum), bareLum: mean(bare, lum), snowBlue: mean(snow, (v) => v[2] - v[0]),
    };
  });
  console.log(`     avaMal day 60: sun ${JSON.stringify(r.sun.map((x) => +x.toFixed(3)))} at ${r.lat}°N; ${r.snow} snowy and ${r.bare} bare cells sampled: luminance ${r.snowLum.toFixed(0)} vs ${r.bareLum.toFixed(0)}, snow blue - red ${r.snowBlue.toFixed(1)}`);
  assert.ok(r.rendering.shadows, 'the sun casts shadows on the terrain');
  assert.ok(r.rendering.fog, 'distance haze');
  // The light comes from the season's sun: [east, north, up] -> [x, y, z] = [e, u, -n].
  const [e, n, u] = r.sun, len = Math.hypot(e, n, u);
  const d = r.rendering.sunDirection;
  assert.ok(u > 0 && r.rendering.sunIntensity > 0, 'a day-time sun');
  assert.ok(Math.abs(d[0] - e / len) < 1e-6 && Math.abs(d[1] - u / len) < 1e-6 && Math.abs(d[2] + n / len) < 1e-6, `light ${d} for sun ${r.sun}`);
  assert.ok(r.snow > 100 && r.bare > 20, `${r.snow} snowy and ${r.bare} bare cells on screen`);
  assert.ok(r.snowLum > r.bareLum + 40, `snow ${r.snowLum} not brighter than bare ground ${r.bareLum}`);
  assert.ok(r.snowBlue > 0, `snow not blue-tinted: blue - red ${r.snowBlue}`);
  await p.screenshot({ path: `${shots}/editor_avamal_day60.png` });
  await p.close();
});

await check('a DEM imported from the page becomes the terrain; a bad file or name is refused with the reader\'s message and the season stays', async () => {
  const demUrl = process.env.SNOWSCAPE_DEM_URL;
  assert.ok(demUrl, 'SNOWSCAPE_DEM_URL is not set (scripts/browser-tests.sh starts that server)');
  const p = await context.newPage();
  p.on('dialog', (d) => d.accept());
  await p.goto(demUrl);
  await p.waitForFunction(() => window.snowscape && window.snowscape.meshTriangles > 0, null, { timeout: 120000 });
  const before = await p.evaluate(() => [window.snowscape.state.width, window.snowscape.state.height, window.snowscape.state.day]);
  // A file the reader refuses: the upload is taken, the job fails naming the file, nothing changes.
  const bad = await p.evaluate(async () => {
    await window.snowscape.importDem(new File(['this is not a grid\n'], 'bad.asc'));
    const t0 = Date.now();
    while (Date.now() - t0 < 30000) {
      const j = window.snowscape.lastJob;
      if (j && j.kind === 'import' && (j.phase === 'failed' || j.phase === 'ended')) return { job: j, upload: window.snowscape.lastImport };
      await new Promise((r) => setTimeout(r, 100));
    }
    return null;
  });
  assert.ok(bad, 'the import job ended');
  assert.equal(bad.upload.status, 202, bad.upload.text);
  assert.equal(bad.job.phase, 'failed');
  assert.ok(bad.job.message.includes('bad.asc'), bad.job.message);
  const after = await p.evaluate(() => [window.snowscape.state.width, window.snowscape.state.height, window.snowscape.state.day]);
  assert.deepEqual(after, before, 'the season is untouched');
  // Names that are not a raster file name are refused before anything is written.
  for (const name of ['../evil.asc', 'notes.txt', 'a b.asc']) {
    const r = await p.evaluate(async (n) => {
      const res = await fetch(`/api/dem?name=${encodeURIComponent(n)}`, { method: 'POST', body: 'x' });
      return [res.status, await res.text()];
    }, name);
    assert.equal(r[0], 400, `${name}: ${r[1]}`);
  }
  // A small ESRI ASCII grid (40 x 30 cells of 10 m, a slope) becomes the terrain.
  const asc = ['ncols 40', 'nrows 30', 'xllcorner 500000', 'yllcorner 5100000', 'cellsize 10', 'NODATA_value -9999']
    .concat(Array.from({ length: 30 }, (_, r) => Array.from({ length: 40 }, (_, c) => (2000 + 8 * r + 3 * c).toFixed(1)).join(' ')))
    .join('\n');
  await p.evaluate(async (text) => { await window.snowscape.importDem(new File([text], 'slope_40x30.asc')); }, asc);
  await p.waitForFunction(() => window.snowscape.state.width === 40 && window.snowscape.state.height === 30, null, { timeout: 60000 });
  const s = await p.evaluate(() => ({ source: window.snowscape.state.source, day: window.snowscape.state.day, tri: window.snowscape.meshTriangles }));
  assert.ok(s.source.includes('slope_40x30.asc'), s.source);
  assert.equal(s.day, 0);
  assert.ok(s.tri > 1000, `${s.tri} triangles`);
  await p.close();
});

await check('a page from another origin cannot connect to the editor', async () => {
  const other = await context.newPage();
  await other.goto('data:text/html,<title>elsewhere</title>');
  const wsUrl = base.replace(/^http/, 'ws') + '/ws';
  const outcome = await other.evaluate((u) => new Promise((resolve) => {
    const ws = new WebSocket(u);
    ws.onopen = () => { resolve('open'); ws.close(); };
    ws.onerror = () => resolve('refused');
    setTimeout(() => resolve('timeout'), 10000);
  }), wsUrl);
  assert.equal(outcome, 'refused');
  await other.close();
});

const tokenUrl = process.env.SNOWSCAPE_TOKEN_URL;
if (tokenUrl) {
  await check('bound beyond loopback, the page needs its token and runs on the cookie it sets', async () => {
    const u = new URL(tokenUrl);
    const bare = `${u.origin}/`;
    assert.ok(u.searchParams.get('token').length === 32, tokenUrl.replace(/token=.*/, 'token=…'));
    assert.equal((await fetch(`${u.origin}/api/state`)).status, 403);
    const ctx = await browser.newContext({ viewport: { width: 800, height: 600 } });
    const p = await ctx.newPage();
    assert.equal((await p.goto(bare)).status(), 403, 'without the token');
    assert.equal((await p.goto(tokenUrl)).status(), 200, 'with the printed URL');
    await p.waitForFunction(() => window.snowscape && window.snowscape.state && window.snowscape.frames >= 10, null, { timeout: 60000 });
    const cookie = (await ctx.cookies()).find((c) => c.name === `snowscape_token_${u.port}`);
    assert.ok(cookie && cookie.httpOnly && cookie.sameSite === 'Strict', JSON.stringify(cookie && { ...cookie, value: '…' }));
    // Reloaded without the token in the URL: its files and its WebSocket go on the cookie.
    assert.equal((await p.goto(bare)).status(), 200, 'on the cookie');
    await p.waitForFunction(() => window.snowscape && window.snowscape.state && window.snowscape.frames >= 10, null, { timeout: 60000 });
    await ctx.close();
  });
}

await browser.close();
const failed = results.filter((r) => r[1] !== 'ok');
console.log(`browser tests: ${results.length - failed.length} passed, ${failed.length} failed`);
process.exit(failed.length ? 1 : 0);
