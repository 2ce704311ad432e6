// Measures the live avalanche's update rate as the page sees it over loopback: the page of a
// running `snowscape serve` (SNOWSCAPE_URL) in headless Chromium loads unstable snow on the
// steepest slope, triggers an avalanche there and counts the binary flow frames (dirty tiles
// of 16-bit heights) and avalanche status messages it receives per second while the flow runs.
// Prints the numbers; asserts only that frames arrived (speed is measured, not tested).
// Run through scripts/live-rate.sh.
import { launchChromium, steepestCellInPage } from './common.mjs';
import assert from 'node:assert/strict';

const url = process.env.SNOWSCAPE_URL;
if (!url) { console.error('SNOWSCAPE_URL is not set'); process.exit(2); }
const seconds = Number(process.env.SNOWSCAPE_SECONDS || 10);
const browser = await launchChromium();
const page = await (await browser.newContext({ viewport: { width: 1200, height: 800 } })).newPage();
page.on('pageerror', (e) => console.log('page error:', e.message));
const t0 = Date.now();
await page.goto(url);
await page.waitForFunction(() => window.snowscape && window.snowscape.state && window.snowscape.grids.powder, null, { timeout: 300000 });
await page.waitForTimeout(2000);
const size = await page.evaluate(() => [window.snowscape.state.width, window.snowscape.state.height]);
console.log(`terrain ${size[0]}x${size[1]}: page load to full state ${Date.now() - t0} ms`);
const site = await steepestCellInPage(page);
await page.evaluate((p) => window.snowscape.send({ type: 'brush', stroke: 1, op: 'add', target: 'unstable', col: p.col, row: p.row, radius_m: 400, strength: 2, value: 0 }), site);
await page.waitForTimeout(1500);
// Count from the trigger, in the page's own clock: frames received until the avalanche ends
// (or SNOWSCAPE_SECONDS pass), over the time from its first status message.
await page.evaluate(() => {
  const a = window.snowscape;
  a.lastAvalanche = null;
  a.rate = { frames0: a.frames, t0: null };
  a.watch = setInterval(() => {
    if (a.lastAvalanche && a.rate.t0 === null) a.rate.t0 = performance.now();
  }, 1);
});
await page.evaluate((p) => window.snowscape.send({ type: 'trigger_avalanche', col: p.col, row: p.row }), site);
await page.waitForFunction(() => window.snowscape.rate.t0 !== null, null, { timeout: 180000 });
await page.waitForFunction((s) => (window.snowscape.lastAvalanche && window.snowscape.lastAvalanche.phase === 'ended')
  || performance.now() - window.snowscape.rate.t0 > s * 1000, seconds, { timeout: (seconds + 120) * 1000 });
const r = await page.evaluate(() => {
  const a = window.snowscape;
  const dt = (performance.now() - a.rate.t0) / 1000;
  return { frames: a.frames - a.rate.frames0, dt, phase: a.lastAvalanche.phase };
});
await browser.close();
console.log(`live avalanche over loopback: ${r.frames} flow frames in ${r.dt.toFixed(2)} s = ${(r.frames / r.dt).toFixed(1)} updates/s (avalanche ${r.phase})`);
assert.ok(r.frames > 0, 'no flow frame arrived');
