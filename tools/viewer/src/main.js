// The page of `tryon view`: plays a run's frames (view.bin: the body, the coarse cloth and the
// output garment every frame) with a timeline, toggles, a colour by stretch, and plots of the
// run's per-frame figures with a cursor tied to the timeline. Bundled with three.js by esbuild
// (tools/viewer, `cargo xtask viewer`) into crates/tryon-view/assets/viewer.js.

import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { parseView } from './view.js';
import { drawPlots, figuresOf } from './plots.js';
import { attachHand, openLive } from './live.js';

const $ = (id) => document.getElementById(id);
const state = {
  frame: 0,
  playing: true,
  speed: 1,
  colour: 'garment',
  framesDrawn: 0,
  ready: false,
  errors: [],
};
// For tests and for people at the console.
window.tryonViewer = state;

function fail(message) {
  state.errors.push(message);
  $('status').textContent = message;
  $('status').className = 'error';
}

async function fetchOk(path) {
  const r = await fetch(path);
  if (!r.ok) throw new Error(`${path}: ${r.status} ${await r.text()}`);
  return r;
}

function meshOf(triangles, count, material) {
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(new Float32Array(count * 3), 3));
  g.setIndex(new THREE.BufferAttribute(new Uint32Array(triangles.flat()), 1));
  return new THREE.Mesh(g, material);
}

/// Per-vertex stretch: the longest incident edge over its length in frame 0.
function stretchField(edges, rest, pos, out) {
  out.fill(1);
  for (let e = 0; e < edges.length; e += 2) {
    const a = edges[e] * 3, b = edges[e + 1] * 3;
    const dx = pos[a] - pos[b], dy = pos[a + 1] - pos[b + 1], dz = pos[a + 2] - pos[b + 2];
    const s = Math.sqrt(dx * dx + dy * dy + dz * dz) / rest[e / 2];
    if (s > out[edges[e]]) out[edges[e]] = s;
    if (s > out[edges[e + 1]]) out[edges[e + 1]] = s;
  }
}

/// Area-weighted vertex normals over typed arrays (three's computeVertexNormals goes through
/// attribute accessors, several times slower for a mesh that moves every frame).
function smoothNormals(g) {
  const p = g.attributes.position.array;
  const idx = g.index.array;
  if (!g.attributes.normal) g.setAttribute('normal', new THREE.BufferAttribute(new Float32Array(p.length), 3));
  const n = g.attributes.normal.array;
  n.fill(0);
  for (let t = 0; t < idx.length; t += 3) {
    const a = idx[t] * 3, b = idx[t + 1] * 3, c = idx[t + 2] * 3;
    const ux = p[b] - p[a], uy = p[b + 1] - p[a + 1], uz = p[b + 2] - p[a + 2];
    const vx = p[c] - p[a], vy = p[c + 1] - p[a + 1], vz = p[c + 2] - p[a + 2];
    const nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
    n[a] += nx; n[a + 1] += ny; n[a + 2] += nz;
    n[b] += nx; n[b + 1] += ny; n[b + 2] += nz;
    n[c] += nx; n[c + 1] += ny; n[c + 2] += nz;
  }
  for (let i = 0; i < n.length; i += 3) {
    const l = Math.hypot(n[i], n[i + 1], n[i + 2]) || 1;
    n[i] /= l; n[i + 1] /= l; n[i + 2] /= l;
  }
  g.attributes.normal.needsUpdate = true;
}

function centreOf(p) {
  let x = 0, y = 0, z = 0;
  for (let i = 0; i < p.length; i += 3) { x += p[i]; y += p[i + 1]; z += p[i + 2]; }
  const n = Math.max(p.length / 3, 1);
  return new THREE.Vector3(x / n, y / n, z / n);
}

function uniqueEdges(triangles) {
  const seen = new Set();
  const edges = [];
  for (const t of triangles) {
    for (const [a, b] of [[t[0], t[1]], [t[1], t[2]], [t[2], t[0]]]) {
      const key = a < b ? a * 4294967296 + b : b * 4294967296 + a;
      if (!seen.has(key)) { seen.add(key); edges.push(a, b); }
    }
  }
  return Uint32Array.from(edges);
}

function colourRamp(s, c) {
  // 1.0 (and below) blue, 1.1 green, 1.2 and over red.
  const t = Math.min(Math.max((s - 1) / 0.2, 0), 1);
  c.setHSL((1 - t) * 0.66, 0.85, 0.5);
}

function depthRamp(quarterMm, c) {
  // Outside white; inside from yellow (0.25 mm) to red (5 mm and deeper).
  if (quarterMm === 0) { c.setRGB(0.92, 0.92, 0.9); return; }
  const t = Math.min(quarterMm / 20, 1);
  c.setHSL(0.16 * (1 - t), 0.95, 0.5);
}

function softwareGl() {
  const gl = document.createElement('canvas').getContext('webgl2');
  const info = gl && gl.getExtension('WEBGL_debug_renderer_info');
  const name = info ? String(gl.getParameter(info.UNMASKED_RENDERER_WEBGL)) : '';
  gl?.getExtension('WEBGL_lose_context')?.loseContext();
  return /swiftshader|llvmpipe|software/i.test(name);
}

async function main() {
  const run = await (await fetchOk('/api/run')).json();
  // Live (`tryon view SCENE`): frames stream in; else the finished run's view.bin.
  const live = run.live ? await openLive() : null;
  state.live = Boolean(live);
  const figures = live ? live.figures : figuresOf(run);
  const view = live
    ? { header: live.header, source: live.source, get frames() { return live.source.frames; }, frame: (k) => live.source.frame(k) }
    : parseView(await (await fetchOk('/api/view.bin')).arrayBuffer());
  document.title = `tryon view: ${view.header.name}`;
  $('name').textContent = view.header.name;

  // Software GL (SwiftShader, llvmpipe: a browser without a GPU, headless Chromium) draws with
  // every pixel on the CPU: antialiasing is left off there (it halves the frame rate), as with
  // ?aa=0; ?pr=R sets the pixel ratio, which otherwise drops while frames are slow.
  const params = new URLSearchParams(window.location.search);
  state.software = softwareGl();
  const antialias = params.get('aa') !== '0' && !state.software;
  const renderer = new THREE.WebGLRenderer({ canvas: $('scene'), antialias });
  // Live on software GL, the page draws at half resolution from the start: every pixel costs the
  // CPU the scene runs on, and a drawing in progress holds up the frames coming in (measured:
  // drag to frame 35 ms at ratio 1, 28 ms at 0.5, median, headless Chromium on 2 cores).
  const liveSoftware = run.live && state.software;
  state.pixelRatio = Number(params.get('pr')) || (liveSoftware ? 0.5 : window.devicePixelRatio);
  const adaptive = !params.get('pr');
  renderer.setPixelRatio(state.pixelRatio);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xf2f2f0);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x888880, 2.2));
  const sun = new THREE.DirectionalLight(0xffffff, 1.6);
  sun.position.set(1, 2, 1.5);
  scene.add(sun);
  const camera = new THREE.PerspectiveCamera(35, 1, 0.01, 100);
  const controls = new OrbitControls(camera, renderer.domElement);

  const h = view.header;
  // The grabbed particle, drawn as a small ball.
  const knob = new THREE.Mesh(new THREE.SphereGeometry(0.012, 12, 8), new THREE.MeshBasicMaterial({ color: 0xffcc00 }));
  knob.visible = false;
  // The body is closed and faces out: its back faces are never seen. A garment's inside is.
  const body = meshOf(h.body.triangles, h.body.vertices,
    new THREE.MeshLambertMaterial({ color: 0xcdaa96, side: THREE.FrontSide }));
  const garment = meshOf(h.garment.triangles, h.garment.vertices,
    new THREE.MeshLambertMaterial({ vertexColors: true, side: THREE.DoubleSide }));
  garment.geometry.setAttribute('color',
    new THREE.BufferAttribute(new Float32Array(h.garment.vertices * 3), 3));
  const coarse = meshOf(h.coarse.triangles, h.coarse.vertices,
    new THREE.MeshBasicMaterial({ color: 0x203060, wireframe: true }));
  coarse.visible = false;
  scene.add(body, garment, coarse, knob);
  if (h.coarse.vertices === 0) $('show-coarse').disabled = true;

  const garmentColours = h.garment.colours.map((c) => new THREE.Color(c[0] / 255, c[1] / 255, c[2] / 255));
  const vertexGarment = new Uint16Array(h.garment.vertices);
  h.garment.triangles.forEach((t, k) => t.forEach((v) => { vertexGarment[v] = h.garment.triangle_garment[k] || 0; }));
  const edges = uniqueEdges(h.garment.triangles);
  const rest = new Float32Array(edges.length / 2);
  {
    const p0 = view.frame(0).garment;
    for (let e = 0; e < edges.length; e += 2) {
      const a = edges[e] * 3, b = edges[e + 1] * 3;
      rest[e / 2] = Math.hypot(p0[a] - p0[b], p0[a + 1] - p0[b + 1], p0[a + 2] - p0[b + 2]) || 1e-9;
    }
  }
  const field = new Float32Array(h.garment.vertices);
  let paintedAs = null;
  let followFrom = null;
  // The meshes move every frame; they are always in view of a camera framed on the body.
  for (const m of [body, garment, coarse]) m.frustumCulled = false;

  // Whether the picture is out of date (live pages draw only then).
  let dirty = true;
  controls.addEventListener('change', () => { dirty = true; });
  state.dirty = () => { dirty = true; };
  state.showMs = 0;
  state.renderMs = 0;
  function show(k) {
    const t0 = performance.now();
    const f = view.frame(k);
    for (const [mesh, p] of [[body, f.body], [garment, f.garment], [coarse, f.coarse]]) {
      // A hidden mesh is brought up to date when it is shown again.
      if (p.length === 0 || !mesh.visible) continue;
      mesh.geometry.attributes.position.array.set(p);
      mesh.geometry.attributes.position.needsUpdate = true;
      if (mesh !== coarse) smoothNormals(mesh.geometry);
    }
    // Colours change with the frame only when they show stretch or depth.
    const depth = state.colour === 'penetration' && f.depth;
    if (state.colour === 'stretch' || depth || paintedAs !== state.colour) {
      const colours = garment.geometry.attributes.color;
      const c = new THREE.Color();
      if (state.colour === 'stretch') stretchField(edges, rest, f.garment, field);
      for (let v = 0; v < h.garment.vertices; v++) {
        if (state.colour === 'stretch') colourRamp(field[v], c);
        else if (depth) depthRamp(depth[v], c);
        else c.copy(garmentColours[vertexGarment[v]] || garmentColours[0]);
        colours.setXYZ(v, c.r, c.g, c.b);
      }
      colours.needsUpdate = true;
      paintedAs = state.colour;
    }
    // The camera moves with the body's centre (a walk leaves frame 0's view otherwise).
    if (followFrom && $('follow').checked && f.body.length) {
      const c = centreOf(f.body);
      const d = c.clone().sub(followFrom);
      camera.position.add(d);
      controls.target.add(d);
      followFrom = c;
    }
    const grabbed = f.grabbed ?? -1;
    knob.visible = grabbed >= 0;
    if (knob.visible) {
      const p = h.coarse.vertices ? f.coarse : f.garment;
      knob.position.fromArray(p, 3 * grabbed);
      state.grabbedAt = knob.position.toArray();
    }
    dirty = true;
    state.frame = k;
    state.time = f.time;
    $('frame').textContent = `frame ${k} / ${view.frames - 1}, ${f.time.toFixed(2)} s`;
    $('timeline').value = k;
    drawPlots($('plots'), figures, k, view.frames, seek);
    state.showMs += performance.now() - t0;
  }
  function seek(k) {
    if (live && state.playing) live.send({ type: 'play', on: false });
    state.playing = false;
    $('play').textContent = 'play';
    show(Math.max(0, Math.min(view.frames - 1, k)));
  }
  state.setFrame = seek;

  // Frame the body at frame 0.
  show(0);
  body.geometry.computeBoundingBox();
  garment.geometry.computeBoundingBox();
  const box = body.geometry.boundingBox.union(garment.geometry.boundingBox || body.geometry.boundingBox);
  const centre = box.getCenter(new THREE.Vector3());
  // Far enough that the box's height, and its width at the canvas's shape, fill 85% of the view.
  const extent = box.getSize(new THREE.Vector3());
  const canvas = renderer.domElement;
  const aspect = canvas.clientWidth / Math.max(canvas.clientHeight, 1);
  const half = Math.tan(THREE.MathUtils.degToRad(camera.fov / 2));
  const fit = Math.max(extent.y, extent.x / aspect) / 2 / half / 0.85 + extent.z / 2;
  camera.position.copy(centre).add(new THREE.Vector3(0, 0.1 * extent.y, fit));
  controls.target.copy(centre);
  controls.update();
  followFrom = centreOf(view.frame(0).body);

  $('timeline').max = view.frames - 1;
  $('timeline').addEventListener('input', (e) => seek(Number(e.target.value)));
  $('play').addEventListener('click', () => {
    state.playing = !state.playing;
    $('play').textContent = state.playing ? 'pause' : 'play';
    if (live) {
      live.send({ type: 'play', on: state.playing });
      if (state.playing) show(view.frames - 1);
    }
  });
  if (!view.frame(0).depth) $('colour').querySelector('option[value=penetration]').disabled = true;
  let liveDue = false;
  if (live) {
    const hand = attachHand(THREE, {
      canvas: renderer.domElement, camera, garment, body, controls, live, state, scene,
      fold: {
        draw: () => $('fold-draw').checked,
        shape: () => $('fold-shape').value,
        height: () => Math.min(Math.max(Number($('fold-height').value) || 15, 1), 100) / 1000,
      },
    });
    state.liveFrames = 1;
    // Frames are only taken here; the next animation frame draws the newest (a page slower than
    // the scene skips frames instead of falling behind).
    live.onFrame = (f) => {
      state.liveFrames += 1;
      // What each frame took on the server (ms), for tests and the console.
      state.sceneMs = (state.sceneMs || []).slice(-599).concat([f.ms]);
      hand.frame(f);
      liveDue = true;
    };
    $('fold-tools').hidden = false;
    state.say = (text) => { $('status').textContent = text; };
    live.onAnswer = (m) => {
      if (m.type === 'error') { state.answers = (state.answers || []).concat([m.message]); $('status').textContent = m.message; }
      if (m.type === 'grabbed') $('status').textContent = `holding particle ${m.particle}`;
      if (m.type === 'folded') $('status').textContent = 'fold built; the scene starts over';
    };
    // The scene was built again (a fold): the page starts over on its new meshes.
    live.onHeader = () => window.location.reload();
  }
  $('speed').addEventListener('change', (e) => { state.speed = Number(e.target.value); });
  $('colour').addEventListener('change', (e) => { state.colour = e.target.value; show(state.frame); });
  for (const [id, mesh] of [['show-body', body], ['show-garment', garment], ['show-coarse', coarse]]) {
    $(id).addEventListener('change', (e) => { mesh.visible = e.target.checked; show(state.frame); });
  }

  function resize() {
    const canvas = renderer.domElement;
    const w = canvas.clientWidth, hgt = canvas.clientHeight;
    const r = renderer.getPixelRatio();
    if (canvas.width !== Math.floor(w * r) || canvas.height !== Math.floor(hgt * r)) {
      dirty = true;
      renderer.setSize(w, hgt, false);
      camera.aspect = w / Math.max(hgt, 1);
      camera.updateProjectionMatrix();
    }
  }
  let clock = performance.now();
  let playhead = 0;
  // Slow frames (under 57 a second over 60 frames) lower the pixel ratio, down to half.
  let window0 = [performance.now(), 0];
  function adapt(now) {
    if (!adaptive || ++window0[1] < 60) return;
    const fps = (window0[1] * 1000) / (now - window0[0]);
    if (fps < 57 && state.pixelRatio > 0.5) {
      state.pixelRatio = Math.max(0.5, state.pixelRatio - 0.25);
      renderer.setPixelRatio(state.pixelRatio);
    }
    window0 = [now, 0];
  }
  // Live pages draw on demand, so frames a second say nothing: a picture that takes over 8 ms
  // on average over 30 (software GL) lowers the pixel ratio, down to half, to keep the page's
  // thread free for the scene's frames.
  let liveWindow = [0, 0];
  function adaptLive(ms) {
    if (!adaptive) return;
    liveWindow = [liveWindow[0] + ms, liveWindow[1] + 1];
    if (liveWindow[1] < 30) return;
    if (liveWindow[0] / liveWindow[1] > 8 && state.pixelRatio > 0.5) {
      state.pixelRatio = Math.max(0.5, state.pixelRatio - 0.25);
      renderer.setPixelRatio(state.pixelRatio);
    }
    liveWindow = [0, 0];
  }
  function tick(now) {
    // requestAnimationFrame's time can be earlier than the clock read when the loop started.
    const dt = Math.max(0, (now - clock) / 1000);
    clock = Math.max(clock, now);
    if (live) {
      if (liveDue) {
        liveDue = false;
        $('timeline').max = view.frames - 1;
        if (state.playing) show(view.frames - 1);
      }
      playhead = state.frame;
    } else if (state.playing && view.frames > 1) {
      playhead = (playhead + dt * h.fps * state.speed) % view.frames;
      const k = Math.floor(playhead);
      if (k !== state.frame) show(k);
    } else {
      playhead = state.frame;
    }
    resize();
    controls.update();
    // Live, a picture is drawn only when something changed (a frame came, the camera moved, a
    // toggle): the page's thread is then free to take the scene's frames as they come.
    if (live && !dirty) {
      requestAnimationFrame(tick);
      return;
    }
    dirty = false;
    const r0 = performance.now();
    renderer.render(scene, camera);
    state.renderMs += performance.now() - r0;
    state.framesDrawn += 1;
    if (!live) adapt(performance.now());
    else adaptLive(performance.now() - r0);
    requestAnimationFrame(tick);
  }
  requestAnimationFrame(tick);
  $('status').textContent = live
    ? `live at ${h.fps} fps; ${h.garment.vertices} garment vertices; press on the cloth to drag it`
    : `${view.frames} frames at ${h.fps} fps; ${h.garment.vertices} garment vertices`;
  state.garmentVertices = h.garment.vertices;
  state.ready = true;
}

main().catch((e) => fail(String(e && e.message ? e.message : e)));
