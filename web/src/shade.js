// Colours of a cell for each shading mode: snow depth, layers, the stability map of
// Cordonnier et al. 2018 Fig. 11 (purple where unstable or powder snow lies on top, blue for
// compacted and stable snow, black without snow), and the overlays.
const ROCK = [0.45, 0.42, 0.38];
const LAYER = { compacted: [0.55, 0.62, 0.72], stable: [0.96, 0.97, 1.0], unstable: [0.95, 0.45, 0.3], powder: [0.75, 0.92, 1.0] };
const VIRIDIS = [[0.267, 0.005, 0.329], [0.229, 0.322, 0.546], [0.128, 0.567, 0.551], [0.369, 0.789, 0.383], [0.993, 0.906, 0.144]];
const ranges = {};

function viridis(t, out) {
  t = Number.isFinite(t) ? Math.min(1, Math.max(0, t)) : 0;
  const x = t * (VIRIDIS.length - 1);
  const i = Math.min(VIRIDIS.length - 2, Math.floor(x));
  const f = x - i;
  for (let c = 0; c < 3; c++) out[c] = VIRIDIS[i][c] * (1 - f) + VIRIDIS[i + 1][c] * f;
}

function range(name, g) {
  const r = ranges[name];
  if (r && r.g === g && r.n === g.length) return r;
  let lo = Infinity, hi = -Infinity;
  for (let i = 0; i < g.length; i++) { const v = g[i]; if (v < lo) lo = v; if (v > hi) hi = v; }
  return (ranges[name] = { g, n: g.length, lo, hi: hi > lo ? hi : lo + 1 });
}

export function colourOf(mode, grids, k, depth, flow, out) {
  const snowShare = Math.min(1, depth / 0.3);
  if (flow > 0.01) { out[0] = 0.85; out[1] = 0.1; out[2] = 0.1; return; }
  switch (mode) {
    case 'layers': {
      if (depth <= 0) { out[0] = ROCK[0]; out[1] = ROCK[1]; out[2] = ROCK[2]; return; }
      out[0] = out[1] = out[2] = 0;
      for (const l of ['compacted', 'stable', 'unstable', 'powder']) {
        const w = (grids[l] ? grids[l][k] : 0) / depth;
        for (let c = 0; c < 3; c++) out[c] += w * LAYER[l][c];
      }
      for (let c = 0; c < 3; c++) out[c] = ROCK[c] * (1 - snowShare) + out[c] * snowShare;
      return;
    }
    case 'stability': {
      const top = (grids.unstable ? grids.unstable[k] : 0) + (grids.powder ? grids.powder[k] : 0);
      const on = Math.min(1, top / 0.02), present = Math.min(1, depth / 0.02);
      const blue = [0.18, 0.38, 0.85], purple = [0.6, 0.2, 0.72];
      for (let c = 0; c < 3; c++) out[c] = present * (blue[c] * (1 - on) + purple[c] * on);
      return;
    }
    case 'temperature': case 'sun': case 'wind': case 'avalanche_probability': case 'ski_area': {
      const g = grids[mode];
      if (!g) break;
      const r = mode === 'avalanche_probability' || mode === 'ski_area' ? { lo: 0, hi: 1 } : range(mode, g);
      viridis((g[k] - r.lo) / (r.hi - r.lo), out);
      return;
    }
    default: break;
  }
  // Snow depth: rock to white, deep snow bluish.
  const deep = Math.min(1, depth / 4);
  for (let c = 0; c < 3; c++) {
    const snow = [1 - 0.25 * deep, 1 - 0.12 * deep, 1][c];
    out[c] = ROCK[c] * (1 - snowShare) + snow * snowShare;
  }
}
