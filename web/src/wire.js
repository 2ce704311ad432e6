// Decoder of the server's binary tile frames (crates/editor/src/wire.rs documents the layout).
// The magic number, the nodata code and the channel names by id are the server's
// (GET /api/protocol, crates/editor/src/page_protocol.rs): every frame is refused until
// setProtocol has them.
const protocol = { magic: null, nodata: null, channels: [] };

export function setProtocol(p) {
  protocol.magic = p.frame_magic;
  protocol.nodata = p.nodata;
  protocol.channels = p.channels.slice();
}

// Decodes `buf` (ArrayBuffer) into `grids` (name -> Float32Array of width*height); returns
// { channel, tiles: [[tx, ty]...], tile, width, height } or null for a malformed frame.
export function applyFrame(buf, grids) {
  const dv = new DataView(buf);
  if (buf.byteLength < 32 || protocol.magic === null || dv.getUint32(0, true) !== protocol.magic) return null;
  const channel = protocol.channels[dv.getUint8(4)];
  if (!channel) return null;
  const tile = dv.getUint16(6, true);
  const width = dv.getUint32(8, true);
  const height = dv.getUint32(12, true);
  const offset = dv.getFloat32(16, true);
  const scale = dv.getFloat32(20, true);
  const n = dv.getUint32(28, true);
  let g = grids[channel];
  if (!g || g.length !== width * height) {
    g = grids[channel] = new Float32Array(width * height);
  }
  let o = 32;
  const tiles = [];
  for (let k = 0; k < n; k++) {
    if (o + 4 > buf.byteLength) return null;
    const tx = dv.getUint16(o, true);
    const ty = dv.getUint16(o + 2, true);
    o += 4;
    const c0 = tx * tile, r0 = ty * tile;
    const w = Math.min(tile, width - c0), h = Math.min(tile, height - r0);
    if (w <= 0 || h <= 0 || o + 2 * w * h > buf.byteLength) return null;
    for (let r = 0; r < h; r++) {
      const row = (r0 + r) * width + c0;
      for (let c = 0; c < w; c++) {
        const q = dv.getUint16(o, true);
        g[row + c] = q === protocol.nodata ? NaN : offset + q * scale;
        o += 2;
      }
    }
    tiles.push([tx, ty]);
  }
  return { channel, tiles, tile, width, height };
}
