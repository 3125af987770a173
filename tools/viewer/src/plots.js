// Plots of a run's per-frame figures (stats.json's `per_frame`: the judged frames) on a canvas,
// one strip per figure, with a cursor at the frame shown; a click seeks to the frame under it.

const FIGURES = [
  { key: 'max_penetration_m', label: 'max penetration (mm)', scale: 1000, colour: '#c0392b' },
  { key: 'p99_penetration_m', label: 'p99 penetration (mm)', scale: 1000, colour: '#e67e22' },
  { key: 'max_stretch', label: 'max stretch', scale: 1, colour: '#2c3e90' },
  { key: 'contacts', label: 'contacts', scale: 1, colour: '#27ae60' },
  { key: 'retries', label: 'substep retries', scale: 1, colour: '#8e44ad' },
];

// The strips are drawn once into a canvas of their own; each frame copies it and draws the
// cursor.
let cache = null;

/// The run's figures per judged frame: stats.json's `per_frame`, with each stage's ms
/// (`frame_ms`, in the same order) as `ms:<stage>`.
export function figuresOf(run) {
  const ms = run.frame_ms || [];
  return (run.per_frame || []).map((p, i) => {
    const f = { ...p };
    for (const [stage, v] of Object.entries(ms[i] || {})) f[`ms:${stage}`] = v;
    return f;
  });
}

const STAGE_COLOURS = ['#1f77b4', '#ff7f0e', '#2ca02c', '#d62728', '#9467bd', '#8c564b', '#e377c2', '#7f7f7f', '#bcbd22', '#17becf'];

/// One strip per stage that took on average over 0.05 ms a frame, slowest first.
function stageFigures(perFrame) {
  const sums = new Map();
  for (const p of perFrame) {
    for (const [k, v] of Object.entries(p)) {
      if (k.startsWith('ms:')) sums.set(k, (sums.get(k) || 0) + v);
    }
  }
  return [...sums.entries()]
    .filter(([, sum]) => sum / Math.max(perFrame.length, 1) > 0.05)
    .sort((a, b) => b[1] - a[1])
    .map(([key], i) => ({ key, label: `${key.slice(3)} (ms)`, scale: 1, colour: STAGE_COLOURS[i % STAGE_COLOURS.length] }));
}

export function drawPlots(canvas, perFrame, current, frames, seek) {
  const w = canvas.clientWidth;
  // A live run's figures grow in place: their count is part of the key.
  if (!cache || cache.width !== w || cache.perFrame !== perFrame || cache.count !== perFrame.length) {
    cache = document.createElement('canvas');
    cache.perFrame = perFrame;
    cache.count = perFrame.length;
    drawStrips(cache, w, perFrame, frames);
  }
  if (canvas.width !== cache.width) canvas.width = cache.width;
  if (canvas.height !== cache.height) canvas.height = cache.height;
  const ctx = canvas.getContext('2d');
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  ctx.drawImage(cache, 0, 0);
  const x = 4 + ((canvas.width - 8) * current) / Math.max(frames - 1, 1);
  ctx.strokeStyle = '#000';
  ctx.beginPath();
  ctx.moveTo(x, 0);
  ctx.lineTo(x, canvas.height);
  ctx.stroke();
  canvas.onclick = (e) => {
    const r = canvas.getBoundingClientRect();
    seek(Math.round(((e.clientX - r.left - 4) / (canvas.width - 8)) * (frames - 1)));
  };
}

function drawStrips(canvas, w, perFrame, frames) {
  const ctx = canvas.getContext('2d');
  const figures = FIGURES.filter((f) => perFrame.some((p) => typeof p[f.key] === 'number'))
    .concat(stageFigures(perFrame));
  const strip = 46;
  canvas.width = w;
  canvas.height = Math.max(strip * figures.length, 1);
  ctx.font = '11px sans-serif';
  const x = (k) => 4 + ((w - 8) * k) / Math.max(frames - 1, 1);
  figures.forEach((f, i) => {
    const top = i * strip;
    const values = perFrame.map((p) => [p.frame, (p[f.key] || 0) * f.scale]);
    const top_ = Math.max(...values.map((v) => v[1]), 0);
    const hi = top_ > 0 ? top_ : 1;
    const lo = Math.min(...values.map((v) => v[1]), 0);
    const y = (v) => top + strip - 6 - ((strip - 20) * (v - lo)) / (hi - lo || 1);
    ctx.fillStyle = '#555';
    ctx.fillText(`${f.label}: max ${Number(top_.toPrecision(4))}`, 6, top + 11);
    ctx.strokeStyle = f.colour;
    ctx.beginPath();
    values.forEach(([k, v], j) => (j ? ctx.lineTo(x(k), y(v)) : ctx.moveTo(x(k), y(v))));
    ctx.stroke();
  });
}
