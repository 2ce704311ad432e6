// The live avalanche stream as a bare WebSocket client receives it over loopback (no page, no
// rendering): connects to a running `snowscape serve` (SNOWSCAPE_URL), decodes the grids with the
// page's own decoder, loads unstable snow on the steepest slope, triggers an avalanche there and
// counts the flow frames per second until it ends (or SNOWSCAPE_SECONDS pass). Separates the
// server's stream rate from the browser's rendering. Needs `node --experimental-websocket` on
// Node 20 (a global WebSocket from Node 22). Run through scripts/live-rate.sh.
import assert from 'node:assert/strict';
import { applyFrame, setProtocol } from '../src/wire.js';
import { steepestCell } from './common.mjs';

const url = process.env.SNOWSCAPE_URL;
if (!url) { console.error('SNOWSCAPE_URL is not set'); process.exit(2); }
const seconds = Number(process.env.SNOWSCAPE_SECONDS || 10);
// The frame layout comes from the server, as the page reads it (without it every frame is
// refused and the wait below would time out).
// The URL `snowscape serve` printed carries the access token the data needs (?token=).
const token = new URL(url).searchParams.get('token') || '';
const origin = new URL(url).origin;
const proto = await fetch(new URL('/api/protocol', origin), { headers: { 'X-Snowscape-Token': token } });
assert.ok(proto.ok, `GET /api/protocol: HTTP ${proto.status}`);
setProtocol(await proto.json());
const grids = {};
let state = null, avalanche = null, frames = 0, flowFrames = 0, bytes = 0;
const ws = new WebSocket(`${origin.replace(/^http/, 'ws')}/ws?token=${token}`);
ws.binaryType = 'arraybuffer';
ws.onerror = () => { console.error('the WebSocket failed'); process.exit(1); };
ws.onmessage = (ev) => {
  if (typeof ev.data === 'string') {
    const m = JSON.parse(ev.data);
    if (m.type === 'state') state = m;
    if (m.type === 'avalanche') avalanche = m;
  } else {
    const f = applyFrame(ev.data, grids);
    frames++;
    if (f && f.channel === 'flow') { flowFrames++; bytes += ev.data.byteLength; }
  }
};
const until = async (cond, ms) => {
  const t = Date.now();
  while (!cond()) {
    if (Date.now() - t > ms) throw new Error('timed out');
    await new Promise((r) => setTimeout(r, 5));
  }
};
await until(() => state && grids.bedrock && grids.powder, 300000);
const { width: w, height: h } = state;
const best = steepestCell(w, h, grids.bedrock);
ws.send(JSON.stringify({ type: 'brush', stroke: 1, op: 'add', target: 'unstable', col: best.col, row: best.row, radius_m: 400, strength: 2, value: 0 }));
await new Promise((r) => setTimeout(r, 1500));
ws.send(JSON.stringify({ type: 'trigger_avalanche', col: best.col, row: best.row }));
await until(() => avalanche, 180000);
const t0 = performance.now(), f0 = flowFrames, b0 = bytes;
await until(() => avalanche.phase === 'ended' || performance.now() - t0 > seconds * 1000, (seconds + 120) * 1000);
const dt = (performance.now() - t0) / 1000, n = flowFrames - f0;
ws.close();
console.log(`bare WebSocket client over loopback, ${w}x${h}: ${n} flow frames in ${dt.toFixed(2)} s = ${(n / dt).toFixed(1)} updates/s, ${((bytes - b0) / Math.max(n, 1) / 1024).toFixed(1)} KiB per frame (avalanche ${avalanche.phase})`);
assert.ok(n > 0, 'no flow frame arrived');
