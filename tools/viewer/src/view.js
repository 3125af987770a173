// view.bin, as tryon-io's `ViewWriter` writes it (little-endian): "TRYONVW1", a u32 header length,
// the header (JSON, padded with spaces to a multiple of 4 bytes), then every frame at a fixed
// size: its time (f32), then the body's, the coarse cloth's and the garment's positions (f32 x, y,
// z each, in the counts the header gives), then, when the header's `depth` is set, one byte per
// garment vertex (its depth in the body in quarter millimetres) padded to a multiple of 4 bytes.

export function parseView(buffer) {
  const magic = new TextDecoder().decode(new Uint8Array(buffer, 0, 8));
  if (magic !== 'TRYONVW1') throw new Error('not a tryon view file');
  const length = new DataView(buffer).getUint32(8, true);
  const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buffer, 12, length)));
  const start = 12 + length;
  const counts = [header.body.vertices, header.coarse.vertices, header.garment.vertices];
  const floats = 1 + 3 * counts.reduce((a, b) => a + b, 0);
  const depthBytes = header.depth ? Math.ceil(counts[2] / 4) * 4 : 0;
  const frameBytes = 4 * floats + depthBytes;
  const frames = Math.floor((buffer.byteLength - start) / frameBytes);
  return {
    header,
    frames,
    frame(k) {
      const at0 = start + k * frameBytes;
      const all = new Float32Array(buffer, at0, floats);
      let at = 1;
      const take = (n) => { const p = all.subarray(at, at + 3 * n); at += 3 * n; return p; };
      return {
        time: all[0],
        body: take(counts[0]),
        coarse: take(counts[1]),
        garment: take(counts[2]),
        depth: header.depth ? new Uint8Array(buffer, at0 + 4 * floats, counts[2]) : null,
      };
    },
  };
}
