// Shared by the browser test and the live-rate measurements.
import { chromium } from 'playwright-core';

// Headless Debian Chromium with software WebGL, quiet on a closed network.
export function launchChromium() {
  return chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
      '--disable-component-update', '--disable-sync', '--use-angle=swiftshader', '--enable-unsafe-swiftshader'],
  });
}

// The cell with the steepest bedrock (central differences), 8 cells away from the border.
export function steepestCell(width, height, bedrock) {
  let best = [0, 0, 0];
  for (let r = 8; r < height - 8; r++) for (let c = 8; c < width - 8; c++) {
    const i = r * width + c;
    const dz = Math.abs(bedrock[i + 1] - bedrock[i - 1]) + Math.abs(bedrock[i + width] - bedrock[i - width]);
    if (dz > best[0]) best = [dz, c, r];
  }
  return { col: best[1], row: best[2] };
}

// The same, evaluated inside the page on its decoded grids.
export const steepestCellInPage = (page) => page.evaluate(
  `(${steepestCell})(window.snowscape.state.width, window.snowscape.state.height, window.snowscape.grids.bedrock)`);
