// Drives the live page of `tryon view SCENE` in headless Chromium (Debian's, /usr/bin/chromium)
// with playwright-core: waits for frames, presses on the garment in the middle of the view,
// drags the pointer up and to the side for about 1.5 s, lets go, and records where the grabbed
// particle was before and after, each drag's time to the first frame that applied it, and the
// frames a second drawn. Then it sends the server garbage on a second socket (text that is not
// JSON, an unknown request, coordinates out of range, an oversized message, a binary one) and
// keeps what the server answered and whether frames still come. Before the drag it draws a fold
// line on the garment (P3) and waits for the page to start over on the scene built again with it.
// Prints one JSON object; the screenshots go into OUTDIR.
//   node test/live.mjs URL OUTDIR
import { chromium } from 'playwright-core';
import { mkdirSync } from 'node:fs';

const [url, out] = process.argv.slice(2);
mkdirSync(out, { recursive: true });
const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
  args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
    '--disable-background-networking', '--disable-component-update', '--disable-sync',
    '--enable-unsafe-swiftshader', '--use-angle=swiftshader'],
});
const result = { errors: [] };
const viewer = (page, f) => page.evaluate(f);
try {
  const page = await browser.newPage({ viewport: { width: 1280, height: 800 } });
  page.on('console', (m) => { if (m.type() === 'error') result.errors.push(m.text()); });
  page.on('pageerror', (e) => result.errors.push(String(e)));
  await page.goto(url);
  await page.waitForFunction(() => window.tryonViewer && (window.tryonViewer.ready || window.tryonViewer.errors.length), null, { timeout: 60000 });
  result.page_errors = await viewer(page, () => window.tryonViewer.errors);
  result.live = await viewer(page, () => window.tryonViewer.live);
  await page.waitForTimeout(2000);
  const d0 = await viewer(page, () => [window.tryonViewer.framesDrawn, window.tryonViewer.liveFrames, performance.now()]);
  await page.waitForTimeout(2000);
  const d1 = await viewer(page, () => [window.tryonViewer.framesDrawn, window.tryonViewer.liveFrames, performance.now()]);
  result.fps = ((d1[0] - d0[0]) * 1000) / (d1[2] - d0[2]);
  result.scene_fps = ((d1[1] - d0[1]) * 1000) / (d1[2] - d0[2]);
  result.render_ms = await viewer(page, () => window.tryonViewer.renderMs / window.tryonViewer.framesDrawn);
  result.show_ms = await viewer(page, () => window.tryonViewer.showMs / window.tryonViewer.framesDrawn);
  result.pixel_ratio = await viewer(page, () => window.tryonViewer.pixelRatio);
  // A ridge drawn upward from a point low on the garment: the scene is built again with it and
  // the page starts over on the new meshes.
  const before = await viewer(page, () => window.tryonViewer.garmentVertices);
  await page.check('#fold-draw');
  const p = await viewer(page, () => window.tryonViewer.clothPoint());
  if (p) {
    const reloaded = page.waitForEvent('load', { timeout: 120000 });
    // Up and across the front, off the middle (a line along a row of vertices adds none).
    await page.mouse.move(p.x + 20, p.y + 60);
    await page.mouse.down();
    for (let i = 1; i <= 40; i++) {
      await page.mouse.move(p.x + 20 + i, p.y + 60 - 3 * i);
      await page.waitForTimeout(20);
    }
    await page.locator('#scene').screenshot({ path: `${out}/live-fold-drawn.png` });
    await page.mouse.up();
    result.fold_points = await viewer(page, () => window.tryonViewer.foldPoints);
    // What the page said, should it not start over.
    reloaded.catch(() => {});
    await page.waitForTimeout(2000);
    result.fold_status = await viewer(page, () => document.getElementById('status').textContent).catch(() => 'reloaded');
    await reloaded;
    await page.waitForFunction(() => window.tryonViewer && (window.tryonViewer.ready || window.tryonViewer.errors.length), null, { timeout: 60000 });
    await page.waitForTimeout(1500);
    result.fold = { before, after: await viewer(page, () => window.tryonViewer.garmentVertices) };
    await page.locator('#scene').screenshot({ path: `${out}/live-fold-built.png` });
  }
  await page.uncheck('#fold-draw').catch(() => {});
  await page.locator('#scene').screenshot({ path: `${out}/live-before.png` });
  const at = await viewer(page, () => window.tryonViewer.clothPoint());
  result.press = at;
  result.drawing_before_drag = await viewer(page, () => document.getElementById('fold-draw').checked);
  if (at) {
    await page.mouse.move(at.x, at.y);
    await page.mouse.down();
    await page.waitForTimeout(200);
    result.grabbed = await viewer(page, () => window.tryonViewer.grabbed);
    result.grabbed_from = await viewer(page, () => window.tryonViewer.grabbedAt);
    for (let i = 1; i <= 50; i++) {
      await page.mouse.move(at.x + 3 * i, at.y - 4 * i);
      await page.waitForTimeout(30);
    }
    await page.waitForTimeout(300);
    result.grabbed_to = await viewer(page, () => window.tryonViewer.grabbedAt);
    await page.locator('#scene').screenshot({ path: `${out}/live-dragged.png` });
    await page.mouse.up();
    await page.waitForTimeout(300);
    result.after_release = await viewer(page, () => window.tryonViewer.grabbed);
    result.latencies = await viewer(page, () => window.tryonViewer.latencies);
    result.scene_ms = await viewer(page, () => window.tryonViewer.sceneMs.slice(-90));
  }
  // Garbage on a second socket: the server answers each with an error and goes on.
  result.garbage = await page.evaluate(() => new Promise((resolve) => {
    const ws = new WebSocket(`ws://${location.host}/api/live`);
    const answers = [];
    let closed = null;
    ws.onmessage = (e) => { if (typeof e.data === 'string') { const m = JSON.parse(e.data); if (m.type !== 'header') answers.push(m.message); } };
    ws.onclose = (e) => { closed = e.code; };
    ws.onopen = () => {
      ws.send('not json');
      ws.send('{"type":"jump"}');
      ws.send('{"type":"drag","target":[1e9,0,0],"seq":1}');
      ws.send('{"type":"grab","point":[50,50,50],"seq":2}');
      ws.send(JSON.stringify({ type: 'release', seq: 3, pad: 'x'.repeat(5000) }));
      ws.send(new Uint8Array([1, 2, 3]));
      setTimeout(() => ws.send('y'.repeat(100000)), 300);
      setTimeout(() => resolve({ answers, closed }), 1500);
    };
  }));
  const f0 = await viewer(page, () => window.tryonViewer.liveFrames);
  await page.waitForTimeout(1000);
  result.frames_after_garbage = (await viewer(page, () => window.tryonViewer.liveFrames)) - f0;
  await page.selectOption('#colour', 'penetration');
  await page.waitForTimeout(300);
  await page.locator('#scene').screenshot({ path: `${out}/live-penetration.png` });
  result.answers = await viewer(page, () => window.tryonViewer.answers || []);
} catch (e) {
  result.errors.push(`driver: ${e}`);
} finally {
  await browser.close();
}
console.log(JSON.stringify(result));
