// Measures how long a season step takes to show in the page after the server finishes it: the
// page of a running `snowscape serve` (SNOWSCAPE_URL) in headless Chromium steps the season
// SNOWSCAPE_DAYS days (default 1), and reports, in the page's clock, the server's step time
// (job start to its `ended` message), the time from that message to the last tile frame, and
// to the first render after it (the mesh patched in place and drawn). Prints the numbers;
// asserts only that frames arrived (speed is measured, not tested). Run through
// scripts/step-latency.sh.
import { launchChromium } from './common.mjs';
import assert from 'node:assert/strict';

const url = process.env.SNOWSCAPE_URL;
if (!url) { console.error('SNOWSCAPE_URL is not set'); process.exit(2); }
const days = Number(process.env.SNOWSCAPE_DAYS || 1);
const repeats = Number(process.env.SNOWSCAPE_REPEATS || 3);
const browser = await launchChromium();
const page = await (await browser.newContext({ viewport: { width: 1200, height: 800 } })).newPage();
page.on('pageerror', (e) => console.log('page error:', e.message));
await page.goto(url + (process.env.SNOWSCAPE_NO_SHADOWS ? (url.includes('?') ? '&' : '?') + 'noshadows' : ''));
await page.waitForFunction(() => window.snowscape && window.snowscape.state && window.snowscape.meshTriangles > 0, null, { timeout: 300000 });
await page.waitForTimeout(3000);
const size = await page.evaluate(() => [window.snowscape.state.width, window.snowscape.state.height, window.snowscape.meshTriangles]);
for (let k = 0; k < repeats; k++) {
  const r = await page.evaluate(async (d) => {
    const a = window.snowscape;
    const frames0 = a.frames, renders0 = a.renders, patches0 = a.patches || 0, t0 = performance.now();
    a.lastJob = null;
    a.send({ type: 'step', days: d });
    while (!(a.lastJob && a.lastJob.kind === 'step' && a.lastJob.phase === 'ended')) {
      await new Promise((res) => setTimeout(res, 5));
      if (performance.now() - t0 > 600000) return null;
    }
    const ended = a.lastJobAt;
    // The frames of the step and the render that shows them: quiet for 1 s after both.
    while (performance.now() - Math.max(a.lastFrameAt || 0, a.lastRenderAt || 0) < 1000) {
      await new Promise((res) => setTimeout(res, 20));
    }
    return {
      step_ms: ended - t0,
      frames: a.frames - frames0,
      last_frame_ms: (a.lastFrameAt || ended) - ended,
      shown_ms: a.lastRenderAt - ended,
      renders: a.renders - renders0,
      patches: (a.patches || 0) - patches0,
      day: a.state.day,
    };
  }, days);
  assert.ok(r, 'the step ended');

  console.log(`${size[0]}x${size[1]} (${size[2]} triangles drawn), step ${days} d to day ${r.day.toFixed(2)}: server ${r.step_ms.toFixed(0)} ms; ` +
    `after its end: last of ${r.frames} tile frames +${r.last_frame_ms.toFixed(0)} ms, shown (mesh patched and drawn) +${r.shown_ms.toFixed(0)} ms ` +
    `(${r.patches} mesh patches, ${r.renders} draws)`);
}
await browser.close();
