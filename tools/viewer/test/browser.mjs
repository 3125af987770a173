// Drives the `tryon view` page in headless Chromium (Debian's, /usr/bin/chromium) with
// playwright-core: loads it, measures the frames it draws a second while playing, scrubs the
// timeline to a frame, switches the colour to stretch and then to depth in the body, and
// screenshots each state. Prints one
// JSON object (what it measured, the console's errors) for the Rust test to judge; the
// screenshots go into OUTDIR.
//   node test/browser.mjs URL OUTDIR
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
const result = { errors: [], console: [] };
try {
  const page = await browser.newPage({ viewport: { width: 1280, height: 800 } });
  page.on('console', (m) => { if (m.type() === 'error') result.errors.push(m.text()); });
  page.on('pageerror', (e) => result.errors.push(String(e)));
  await page.goto(url + (process.env.VIEW_QUERY || ""));
  await page.waitForFunction(() => window.tryonViewer && (window.tryonViewer.ready || window.tryonViewer.errors.length), null, { timeout: 60000 });
  result.page_errors = await page.evaluate(() => window.tryonViewer.errors);
  // Frames drawn a second while playing, over 3 s, after 2 s in which the page settles (on
  // software GL it lowers its pixel ratio while frames are slow).
  await page.waitForTimeout(2000);
  const d0 = await page.evaluate(() => [window.tryonViewer.framesDrawn, performance.now()]);
  await page.waitForTimeout(3000);
  const d1 = await page.evaluate(() => [window.tryonViewer.framesDrawn, performance.now()]);
  result.fps = ((d1[0] - d0[0]) * 1000) / (d1[1] - d0[1]);
  result.software_gl = await page.evaluate(() => window.tryonViewer.software);
  result.pixel_ratio = await page.evaluate(() => window.tryonViewer.pixelRatio);
  result.frames = await page.evaluate(() => Number(document.getElementById('timeline').max) + 1);
  // Scrub to frame 0, then to the middle frame, as a person drags the slider.
  const scrub = async (k) => {
    await page.evaluate((k) => {
      const t = document.getElementById('timeline');
      t.value = String(k);
      t.dispatchEvent(new Event('input', { bubbles: true }));
    }, k);
    await page.waitForTimeout(300);
    return page.evaluate(() => ({ frame: window.tryonViewer.frame, label: document.getElementById('frame').textContent, playing: window.tryonViewer.playing }));
  };
  result.at_first = await scrub(0);
  await page.locator('#scene').screenshot({ path: `${out}/frame-first.png` });
  const middle = Math.floor(result.frames / 2);
  result.at_middle = await scrub(middle);
  await page.locator('#scene').screenshot({ path: `${out}/frame-middle.png` });
  await page.selectOption('#colour', 'stretch');
  await page.waitForTimeout(300);
  await page.locator('#scene').screenshot({ path: `${out}/stretch-middle.png` });
  result.penetration_enabled = await page.evaluate(() => !document.querySelector('#colour option[value=penetration]').disabled);
  await page.selectOption('#colour', 'penetration');
  await page.waitForTimeout(300);
  await page.locator('#scene').screenshot({ path: `${out}/penetration-middle.png` });
  await page.screenshot({ path: `${out}/page.png` });
} catch (e) {
  result.errors.push(`driver: ${e}`);
} finally {
  await browser.close();
}
console.log(JSON.stringify(result));
