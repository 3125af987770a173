// The live page (`tryon view SCENE`): frames stream in over a WebSocket at /api/live (the first
// message is view.bin's header as JSON, then one binary message per frame, laid out as
// tryon-io's `encode_frame` writes it) and the page's requests go out (grab, drag, release,
// play). The last frames are kept so the timeline can look back while the scene is paused.

const HISTORY = 240;
const HEAD = 32;

function parseFrame(buffer, counts) {
  const dv = new DataView(buffer);
  const points = counts[0] + counts[1] + counts[2];
  const all = new Float32Array(buffer, HEAD, 3 * points);
  let at = 0;
  const take = (n) => { const p = all.subarray(at, at + 3 * n); at += 3 * n; return p; };
  const depthAt = HEAD + 12 * points;
  return {
    frame: dv.getUint32(4, true),
    ack: dv.getUint32(8, true),
    grabbed: dv.getInt32(12, true),
    time: dv.getFloat32(16, true),
    ms: dv.getFloat32(20, true),
    max_penetration_m: dv.getFloat32(24, true),
    max_stretch: dv.getFloat32(28, true),
    body: take(counts[0]),
    coarse: take(counts[1]),
    garment: take(counts[2]),
    depth: buffer.byteLength >= depthAt + counts[2] ? new Uint8Array(buffer, depthAt, counts[2]) : null,
  };
}

/// Opens the live scene; resolves once its header and first frame are in. `source` plays like a
/// view.bin (frames, frame(k)), `figures` are the per-frame plots' values, `onFrame` is called
/// with each new frame, `send` sends a request.
export function openLive() {
  return new Promise((resolve, reject) => {
    const ws = new WebSocket(`ws://${window.location.host}/api/live`);
    ws.binaryType = 'arraybuffer';
    const live = {
      header: null,
      history: [],
      figures: [],
      onFrame: () => {},
      onAnswer: () => {},
      onHeader: () => {},
      send: (request) => { if (ws.readyState === WebSocket.OPEN) ws.send(JSON.stringify(request)); },
      source: null,
    };
    live.source = {
      get frames() { return live.history.length; },
      frame: (k) => live.history[k],
    };
    let started = false;
    ws.onerror = () => reject(new Error('the live connection failed'));
    ws.onclose = () => { if (started) live.onAnswer({ type: 'error', message: 'the live scene closed the connection' }); };
    ws.onmessage = (e) => {
      if (typeof e.data === 'string') {
        const m = JSON.parse(e.data);
        // A new header once started: the scene was built again (a fold was drawn).
        if (m.type === 'header' && started) live.onHeader(m.header);
        else if (m.type === 'header') live.header = m.header;
        else live.onAnswer(m);
        return;
      }
      if (!live.header) return;
      const h = live.header;
      const counts = [h.body.vertices, h.coarse.vertices, h.garment.vertices];
      // A frame of another scene (its header was missed): start again from the scene's header.
      if (e.data.byteLength < HEAD + 12 * (counts[0] + counts[1] + counts[2])) { live.onHeader(null); return; }
      const f = parseFrame(e.data, counts);
      live.history.push(f);
      live.figures.push({ frame: 0, max_penetration_m: f.max_penetration_m, max_stretch: f.max_stretch, 'ms:frame': f.ms });
      if (live.history.length > HISTORY) {
        live.history.splice(0, live.history.length - HISTORY);
        live.figures.splice(0, live.figures.length - HISTORY);
      }
      live.figures.forEach((p, i) => { p.frame = i; });
      if (!started) { started = true; resolve(live); } else live.onFrame(f);
    };
  });
}

/// The user's hand on a live scene: a press on the garment grabs the cloth there, moving the
/// pointer drags it in the plane through the grabbed point facing the camera, releasing lets go.
/// A press elsewhere is left to the camera's controls. Each drag's time to the first frame that
/// applied it is kept in `state.latencies` (ms).
export function attachHand(THREE, { canvas, camera, garment, body, controls, live, state, scene, fold }) {
  const raycaster = new THREE.Raycaster();
  const plane = new THREE.Plane();
  const sent = new Map();
  let seq = 0;
  let holding = false;
  // A fold line being drawn: its points on the garment and its picture.
  let drawing = null;
  // The last line sent: shown until the scene starts over, or the next press (when refused).
  let lastLine = null;
  state.latencies = [];
  state.grabbed = -1;
  // three.js tests a ray against the geometry's bounding sphere and box before its triangles,
  // and both were computed for an earlier frame (the box for the framing): a garment that has
  // moved since was missed wherever it left them.
  const fresh = (mesh) => { mesh.geometry.computeBoundingSphere(); mesh.geometry.computeBoundingBox(); };
  const ray = (e) => {
    const r = canvas.getBoundingClientRect();
    const ndc = new THREE.Vector2(((e.clientX - r.left) / r.width) * 2 - 1, -((e.clientY - r.top) / r.height) * 2 + 1);
    raycaster.setFromCamera(ndc, camera);
    return raycaster.ray;
  };
  canvas.addEventListener('pointerdown', (e) => {
    if (e.button !== 0 || !garment.visible) return;
    if (lastLine) { scene.remove(lastLine); lastLine.geometry.dispose(); lastLine = null; state.dirty(); }
    ray(e);
    fresh(garment);
    const hit = raycaster.intersectObject(garment, false)[0];
    if (!hit) return;
    // The camera's controls do not see this press.
    e.stopImmediatePropagation();
    canvas.setPointerCapture(e.pointerId);
    controls.enabled = false;
    if (fold.draw()) {
      // The scene holds still while the line is drawn: every point then lies on the same
      // garment, which the server carries back to the start as one (a walking garment drawn
      // on over a second put the first points on a place it had left).
      if (state.playing) live.send({ type: 'play', on: false });
      drawing = { points: [hit.point.clone()], line: new THREE.Line(new THREE.BufferGeometry(), new THREE.LineBasicMaterial({ color: 0xff2060 })) };
      drawing.line.frustumCulled = false;
      scene.add(drawing.line);
      return;
    }
    holding = true;
    plane.setFromNormalAndCoplanarPoint(camera.getWorldDirection(new THREE.Vector3()), hit.point);
    live.send({ type: 'grab', point: hit.point.toArray(), seq: ++seq });
  }, { capture: true });
  canvas.addEventListener('pointermove', (e) => {
    if (drawing) {
      ray(e);
      const hit = raycaster.intersectObject(garment, false)[0];
      if (hit && hit.point.distanceTo(drawing.points[drawing.points.length - 1]) > 0.005) {
        drawing.points.push(hit.point.clone());
        // A line's buffer does not grow: a new one each time.
        drawing.line.geometry.dispose();
        drawing.line.geometry = new THREE.BufferGeometry().setFromPoints(drawing.points);
        state.dirty();
      }
      return;
    }
    if (!holding) return;
    const target = ray(e).intersectPlane(plane, new THREE.Vector3());
    if (!target) return;
    live.send({ type: 'drag', target: target.toArray(), seq: ++seq });
    sent.set(seq, performance.now());
  });
  const letGo = () => {
    if (drawing) {
      const { points, line } = drawing;
      drawing = null;
      controls.enabled = true;
      // Playing again: at once if nothing is sent, else after the fold (the scene starts over).
      const resume = () => { if (state.playing) live.send({ type: 'play', on: true }); };
      if (points.length < 2) { scene.remove(line); state.dirty(); resume(); return; }
      // A few points evenly spaced along the line, as a person would click them: the fold is
      // cut along straight segments between them, and a hand's jitter would zigzag it.
      const along = [0];
      for (let i = 1; i < points.length; i++) along.push(along[i - 1] + points[i].distanceTo(points[i - 1]));
      const total = along[along.length - 1];
      const n = Math.max(2, Math.min(8, Math.round(total / 0.03) + 1));
      const picked = Array.from({ length: n }, (_, i) => {
        const at = (total * i) / (n - 1);
        let k = 0;
        while (k < along.length - 2 && along[k + 1] < at) k++;
        return points[k].toArray();
      });
      live.send({ type: 'fold', shape: fold.shape(), height: fold.height(), points: picked, seq: ++seq });
      resume();
      state.foldSent = picked.length;
      state.foldPoints = picked;
      lastLine = line;
      state.say?.(`building the ${fold.shape()} (${picked.length} points); the scene starts over with it`);
      return;
    }
    if (!holding) return;
    holding = false;
    controls.enabled = true;
    live.send({ type: 'release', seq: ++seq });
  };
  // For tests: a point of the canvas (client pixels) where the garment is in front, in the
  // middle of the view and of the garment's height there (the waist: it moves least in a walk),
  // or null.
  state.clothPoint = () => {
    const r = canvas.getBoundingClientRect();
    const hits = [];
    fresh(garment);
    if (body.visible) fresh(body);
    for (let y = 0.1; y <= 0.9; y += 0.02) {
      raycaster.setFromCamera(new THREE.Vector2(0, 1 - y * 2), camera);
      const g = raycaster.intersectObject(garment, false)[0];
      const b = body.visible ? raycaster.intersectObject(body, false)[0] : null;
      if (g && (!b || g.distance < b.distance)) hits.push(y);
    }
    if (!hits.length) return null;
    return { x: r.left + 0.5 * r.width, y: r.top + hits[Math.floor(hits.length / 2)] * r.height };
  };
  canvas.addEventListener('pointerup', letGo);
  canvas.addEventListener('pointercancel', letGo);
  return {
    // A frame came: the drags it applied have their time.
    frame(f) {
      const now = performance.now();
      for (const [s, t] of sent) {
        if (s <= f.ack) { state.latencies.push(now - t); sent.delete(s); }
      }
      state.grabbed = f.grabbed;
    },
  };
}
