// Colours of a cell for each shading mode: snow depth, layers, the stability map of
// Cordonnier et al. 2018 Fig. 11 (purple where unstable or powder snow lies on top, blue for
// compacted and stable snow, black without snow), and the overlays.
const ROCK = [0.45, 0.42, 0.38];
// Bare ground by slope and altitude: grass on gentle, low ground, rock on steep or high ground,
// dark scree on the steepest faces.
const GRASS = [0.34, 0.40, 0.23], SCREE = [0.33, 0.31, 0.29];
// Snow: bright and faintly blue (the sky light fills its shadows with blue); deep snow a little
// bluer, as light scattered inside it is.
// The previews' colours (snow, layers, the Fig. 11 stability map, viridis) are the server's
// (GET /api/protocol, crates/render/src/colour.rs), set in place by setColours before the first
// frame; the arrays start black.
const SNOW = [0, 0, 0], DEEP_SNOW = [0.80, 0.88, 1.0];
const LAYER = { compacted: [0, 0, 0], stable: [0, 0, 0], unstable: [0, 0, 0], powder: [0, 0, 0] };
const VIRIDIS = [[0, 0, 0], [0, 0, 0]];
const BLUE = [0, 0, 0], PURPLE = [0, 0, 0], BLACK = [0, 0, 0], RED = [0.85, 0.1, 0.1];

export function setColours(c) {
  SNOW.splice(0, 3, ...c.snow);
  for (const k of Object.keys(LAYER)) LAYER[k].splice(0, 3, ...c.layers[k]);
  BLACK.splice(0, 3, ...c.stability.no_snow);
  BLUE.splice(0, 3, ...c.stability.stable);
  PURPLE.splice(0, 3, ...c.stability.unstable);
  VIRIDIS.splice(0, VIRIDIS.length, ...c.viridis.map((rgb) => rgb.slice()));
}

// The legend of each shading mode, with a fixed physical range (the same colours mean the same
// values in every tab, at every step and on every terrain): a ramp from `lo` to `hi` (values
// beyond are clamped), or classes.
export const LEGENDS = {
  depth: { title: 'snow depth', unit: 'm', lo: 0, hi: 4, ticks: [0, 1, 2, 3, 4] },
  layers: { title: 'snow layers (mixed by thickness)', classes: [['rock', ROCK], ['compacted', LAYER.compacted], ['stable', LAYER.stable], ['unstable', LAYER.unstable], ['powder', LAYER.powder]] },
  stability: { title: 'stability map (Fig. 11)', classes: [['no snow', BLACK], ['stable or compacted on top', BLUE], ['unstable snow or powder on top', PURPLE]] },
  temperature: { title: 'air temperature', unit: '°C', lo: -20, hi: 15, ticks: [-20, -10, 0, 10, 15] },
  sun: { title: 'direct sun', unit: 'h/day', lo: 0, hi: 12, ticks: [0, 3, 6, 9, 12] },
  wind: { title: 'wind speed (arrows: where it blows)', unit: 'm/s', lo: 0, hi: 20, ticks: [0, 5, 10, 15, 20] },
  avalanche_probability: { title: 'painted release probability', unit: 'per day', lo: 0, hi: 1, ticks: [0, 0.5, 1] },
  ski_area: { title: 'painted skier area', unit: 'share', lo: 0, hi: 1, ticks: [0, 0.5, 1] },
};
export const FLOW_COLOUR = RED;

function viridis(t, out) {
  t = Number.isFinite(t) ? Math.min(1, Math.max(0, t)) : 0;
  const x = t * (VIRIDIS.length - 1);
  const i = Math.min(VIRIDIS.length - 2, Math.floor(x));
  const f = x - i;
  for (let c = 0; c < 3; c++) out[c] = VIRIDIS[i][c] * (1 - f) + VIRIDIS[i + 1][c] * f;
}

// The colour of `value` on the ramp of `mode` (a ramp mode of LEGENDS).
export function rampColour(mode, value, out) {
  if (mode === 'depth') { depthColour(value, out); return; }
  const r = LEGENDS[mode];
  viridis((value - r.lo) / (r.hi - r.lo), out);
}

// The colour of bare ground of slope `tanSlope` (rise over run) at altitude share `alt` (0 at
// the terrain's lowest cell, 1 at its highest): grass below 30° on the lower 60 % of the
// relief, rock above, scree on faces steeper than 45°.
export function bareColour(tanSlope, alt, out) {
  const t = Number.isFinite(tanSlope) ? tanSlope : 0;
  const a = Number.isFinite(alt) ? alt : 0;
  const grass = clamp01((0.58 - t) / 0.2) * clamp01((0.6 - a) / 0.15);
  const scree = clamp01((t - 1.0) / 0.4);
  for (let c = 0; c < 3; c++) {
    const rock = ROCK[c] * (1 - scree) + SCREE[c] * scree;
    out[c] = rock * (1 - grass) + GRASS[c] * grass;
  }
}

function clamp01(x) { return Math.min(1, Math.max(0, x)); }

// Snow depth: bare ground to snow at 30 cm, deep snow bluish (4 m and more).
function depthColour(depth, out, bare = ROCK) {
  const snowShare = Math.min(1, Math.max(0, depth) / 0.3);
  const deep = Math.min(1, Math.max(0, depth) / 4);
  for (let c = 0; c < 3; c++) {
    const snow = SNOW[c] * (1 - deep) + DEEP_SNOW[c] * deep;
    out[c] = bare[c] * (1 - snowShare) + snow * snowShare;
  }
}

// `bare`: the colour of the cell's bare ground ([`bareColour`]), where the shading shows it.
export function colourOf(mode, grids, k, depth, flow, out, bare = ROCK) {
  const snowShare = Math.min(1, depth / 0.3);
  if (flow > 0.01) { out[0] = RED[0]; out[1] = RED[1]; out[2] = RED[2]; return; }
  switch (mode) {
    case 'layers': {
      if (depth <= 0) { out[0] = bare[0]; out[1] = bare[1]; out[2] = bare[2]; return; }
      out[0] = out[1] = out[2] = 0;
      for (const l of ['compacted', 'stable', 'unstable', 'powder']) {
        const w = (grids[l] ? grids[l][k] : 0) / depth;
        for (let c = 0; c < 3; c++) out[c] += w * LAYER[l][c];
      }
      for (let c = 0; c < 3; c++) out[c] = bare[c] * (1 - snowShare) + out[c] * snowShare;
      return;
    }
    case 'stability': {
      const top = (grids.unstable ? grids.unstable[k] : 0) + (grids.powder ? grids.powder[k] : 0);
      const on = Math.min(1, top / 0.02), present = Math.min(1, depth / 0.02);
      for (let c = 0; c < 3; c++) out[c] = present * (BLUE[c] * (1 - on) + PURPLE[c] * on);
      return;
    }
    case 'temperature': case 'sun': case 'wind': case 'avalanche_probability': case 'ski_area': {
      const g = grids[mode];
      if (!g) break;
      rampColour(mode, g[k], out);
      return;
    }
    default: break;
  }
  depthColour(depth, out, bare);
}
