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
        if (m.type === 'header') live.header = m.header;
        else live.onAnswer(m);
        return;
      }
      if (!live.header) return;
      const h = live.header;
      const f = parseFrame(e.data, [h.body.vertices, h.coarse.vertices, h.garment.vertices]);
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
export function attachHand(THREE, { canvas, camera, garment, body, controls, live, state }) {
  const raycaster = new THREE.Raycaster();
  const plane = new THREE.Plane();
  const sent = new Map();
  let seq = 0;
  let holding = false;
  state.latencies = [];
  state.grabbed = -1;
  const ray = (e) => {
    const r = canvas.getBoundingClientRect();
    const ndc = new THREE.Vector2(((e.clientX - r.left) / r.width) * 2 - 1, -((e.clientY - r.top) / r.height) * 2 + 1);
    raycaster.setFromCamera(ndc, camera);
    return raycaster.ray;
  };
  canvas.addEventListener('pointerdown', (e) => {
    if (e.button !== 0 || !garment.visible) return;
    ray(e);
    garment.geometry.computeBoundingSphere();
    const hit = raycaster.intersectObject(garment, false)[0];
    if (!hit) return;
    // The camera's controls do not see this press.
    e.stopImmediatePropagation();
    canvas.setPointerCapture(e.pointerId);
    holding = true;
    controls.enabled = false;
    plane.setFromNormalAndCoplanarPoint(camera.getWorldDirection(new THREE.Vector3()), hit.point);
    live.send({ type: 'grab', point: hit.point.toArray(), seq: ++seq });
  }, { capture: true });
  canvas.addEventListener('pointermove', (e) => {
    if (!holding) return;
    const target = ray(e).intersectPlane(plane, new THREE.Vector3());
    if (!target) return;
    live.send({ type: 'drag', target: target.toArray(), seq: ++seq });
    sent.set(seq, performance.now());
  });
  const letGo = () => {
    if (!holding) return;
    holding = false;
    controls.enabled = true;
    live.send({ type: 'release', seq: ++seq });
  };
  // For tests: a point of the canvas (client pixels) where the garment is in front, low in the
  // middle of the view (a skirt's hem, a shirt's waist), or null.
  state.clothPoint = () => {
    const r = canvas.getBoundingClientRect();
    let best = null;
    for (let y = 0.1; y <= 0.9; y += 0.04) {
      for (let x = 0.4; x <= 0.6; x += 0.05) {
        raycaster.setFromCamera(new THREE.Vector2(x * 2 - 1, 1 - y * 2), camera);
        const g = raycaster.intersectObject(garment, false)[0];
        const b = body.visible ? raycaster.intersectObject(body, false)[0] : null;
        if (g && (!b || g.distance < b.distance) && (!best || y > best.y)) best = { x, y };
      }
    }
    return best && { x: r.left + best.x * r.width, y: r.top + best.y * r.height };
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
