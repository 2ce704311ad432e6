// Screenshots of the editor for the book (docs/src/guide/serve.md): the page on SNOWSCAPE_URL stepped to day
// SNOWSCAPE_DAYS (0: as it opens), its 3D view written to SNOWSCAPE_OUT (PNG).
import { launchChromium } from './common.mjs';

const url = process.env.SNOWSCAPE_URL;
const days = Number(process.env.SNOWSCAPE_DAYS || 0);
const out = process.env.SNOWSCAPE_OUT;
if (!url || !out) { console.error('SNOWSCAPE_URL and SNOWSCAPE_OUT must be set'); process.exit(2); }
const browser = await launchChromium();
const page = await (await browser.newContext({ viewport: { width: 1280, height: 800 } })).newPage();
page.on('pageerror', (e) => console.log('page error:', e.message));
await page.goto(url);
await page.waitForFunction(() => window.snowscape && window.snowscape.state && window.snowscape.frames >= 10, null, { timeout: 120000 });
if (days > 0) {
  await page.evaluate((d) => window.snowscape.send({ type: 'step', days: d }), days);
  await page.waitForFunction((d) => window.snowscape.state.day >= d - 1e-6 && !window.snowscape.state.busy, days, { timeout: 600000 });
}
await page.waitForTimeout(4000);
const t = Date.now();
await page.locator('#view').screenshot({ path: out });
const s = await page.evaluate(() => ({ day: window.snowscape.state.day, sun: window.snowscape.sunElevationDeg, lat: window.snowscape.state.latitude_deg }));
console.log(`${out}: day ${s.day.toFixed(1)}, latitude ${s.lat.toFixed(1)}°, sun ${s.sun.toFixed(1)}° above the horizon (${Date.now() - t} ms)`);
await browser.close();
