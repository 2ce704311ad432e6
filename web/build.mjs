// Builds the page into dist/: bundles src/main.js (three.js from node_modules) with esbuild
// and copies the HTML and CSS.
import { build } from 'esbuild';
import { mkdirSync, copyFileSync } from 'node:fs';

mkdirSync('dist', { recursive: true });
await build({
  entryPoints: ['src/main.js'],
  bundle: true,
  minify: true,
  format: 'esm',
  target: ['chrome110', 'firefox110'],
  outfile: 'dist/main.js',
  logLevel: 'info',
});
for (const f of ['index.html', 'style.css']) copyFileSync(`src/${f}`, `dist/${f}`);
