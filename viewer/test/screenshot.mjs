// Headless browser check of the semap viewer: loads the page, waits for the first rendered
// frame, takes screenshots and asserts that
//   - the mesh is drawn: the share of canvas pixels differing from the clear colour exceeds
//     --min-fraction (UI panels hidden for this shot),
//   - the class toggles work: with every class switched off most of those pixels disappear,
//   - clicking an object box opens its panel (class distribution, point count),
//   - no two object labels shown overlap (labels.js hides the lesser of overlapping ones), also
//     zoomed in on the first object (labels_zoomed.png),
//   - the occupancy grid and scene graph layers (when the folder has them) each change the
//     picture when toggled (layers_on.png, grid_off.png, graph_off.png),
//   - the console shows no errors and no request fails.
// With --live-gap-ms G (a `semap run --view` page) it checks the live view instead: two
// screenshots G ms apart, each after a new snapshot arrived, must show a growing mesh.
// Usage: node test/screenshot.mjs --url URL --out DIR [--min-fraction 0.05] [--chromium PATH]
//        [--live-gap-ms G]
// Exit: 0 pass, 1 an assertion failed, 2 the browser could not be started.
import { chromium } from 'playwright-core';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';

function parseArgs(argv) {
  const args = { url: null, out: null, minFraction: 0.05, chromium: '/usr/bin/chromium', timeoutMs: 90000, liveGapMs: 0 };
  for (let i = 2; i < argv.length; ++i) {
    const key = argv[i];
    const value = argv[i + 1];
    if (key === '--url') args.url = value;
    else if (key === '--out') args.out = value;
    else if (key === '--min-fraction') args.minFraction = Number(value);
    else if (key === '--chromium') args.chromium = value;
    else if (key === '--timeout-ms') args.timeoutMs = Number(value);
    else if (key === '--live-gap-ms') args.liveGapMs = Number(value);
    else { console.log(`unknown argument ${key}`); process.exit(2); }
    ++i;
  }
  if (!args.url || !args.out) {
    console.log('usage: node test/screenshot.mjs --url URL --out DIR [--min-fraction F] [--chromium PATH]');
    process.exit(2);
  }
  return args;
}

const CLEAR = [0x1e, 0x22, 0x28];  // renderer clear colour in src/main.js

// Fraction of pixels of a PNG (decoded by the page itself) that differ from the clear colour.
async function foregroundFraction(page, png) {
  return page.evaluate(async ({ b64, clear }) => {
    const image = new Image();
    image.src = `data:image/png;base64,${b64}`;
    await image.decode();
    const canvas = document.createElement('canvas');
    canvas.width = image.width;
    canvas.height = image.height;
    const context = canvas.getContext('2d');
    context.drawImage(image, 0, 0);
    const data = context.getImageData(0, 0, canvas.width, canvas.height).data;
    let differing = 0;
    for (let i = 0; i < data.length; i += 4) {
      const d = Math.abs(data[i] - clear[0]) + Math.abs(data[i + 1] - clear[1]) + Math.abs(data[i + 2] - clear[2]);
      if (d > 24) ++differing;
    }
    return differing / (canvas.width * canvas.height);
  }, { b64: png.toString('base64'), clear: CLEAR });
}

// Fraction of pixels that differ between two PNGs of the same size (decoded by the page).
async function differingFraction(page, pngA, pngB) {
  return page.evaluate(async ({ a, b }) => {
    const decode = async (b64) => {
      const image = new Image();
      image.src = `data:image/png;base64,${b64}`;
      await image.decode();
      const canvas = document.createElement('canvas');
      canvas.width = image.width;
      canvas.height = image.height;
      canvas.getContext('2d').drawImage(image, 0, 0);
      return canvas.getContext('2d').getImageData(0, 0, canvas.width, canvas.height).data;
    };
    const [da, db] = [await decode(a), await decode(b)];
    let differing = 0;
    for (let i = 0; i < da.length; i += 4) {
      if (Math.abs(da[i] - db[i]) + Math.abs(da[i + 1] - db[i + 1]) + Math.abs(da[i + 2] - db[i + 2]) > 24) ++differing;
    }
    return differing / (da.length / 4);
  }, { a: pngA.toString('base64'), b: pngB.toString('base64') });
}

// The grid and scene graph layers (issue 39): switching each off changes the canvas.
async function layerChecks(page, args, result, problems) {
  result.layer_counts = await page.evaluate(() => window.semapViewer.layerCounts());
  const present = ['grid', 'graph'].filter((name) => result.layer_counts[name]);
  if (present.length === 0) return;
  await page.evaluate(() => { document.body.classList.add('hide-ui'); window.semapViewer.render(); });
  const on = await page.screenshot({ path: path.join(args.out, 'layers_on.png') });
  result.layer_toggle_fraction = {};
  for (const name of present) {
    await page.evaluate((n) => { window.semapViewer.setLayer(n, false); window.semapViewer.render(); }, name);
    const off = await page.screenshot({ path: path.join(args.out, `${name}_off.png`) });
    await page.evaluate((n) => { window.semapViewer.setLayer(n, true); window.semapViewer.render(); }, name);
    const fraction = await differingFraction(page, on, off);
    result.layer_toggle_fraction[name] = fraction;
    if (!(fraction > 0.001)) problems.push(`switching the ${name} layer off changes only ${(100 * fraction).toFixed(3)}% of the canvas`);
  }
  await page.evaluate(() => { document.body.classList.remove('hide-ui'); window.semapViewer.render(); });
  // The plan view a user gets from "view from above", for people to look at (not checked).
  if (result.layer_counts.grid) {
    await page.evaluate(() => { window.semapViewer.viewFromAbove(); window.semapViewer.render(); });
    await page.screenshot({ path: path.join(args.out, 'from_above.png') });
  }
}

// The live view: a first screenshot once a snapshot with a mesh is shown, a second one `gap`
// ms later after a newer snapshot; the mesh must have grown between them.
async function liveCheck(page, args, result, problems) {
  const shot = async (name, afterVersion) => {
    await page.waitForFunction((v) => window.semapViewer.liveVersion !== null && window.semapViewer.liveVersion > v &&
      window.semapViewer.vertexCount() > 0, afterVersion, { timeout: args.timeoutMs });
    await page.waitForTimeout(300);  // the reload of that snapshot finishes drawing
    const state = await page.evaluate(() => ({ version: window.semapViewer.liveVersion, vertices: window.semapViewer.vertexCount() }));
    await page.evaluate(() => window.semapViewer.render());
    const png = await page.screenshot({ path: path.join(args.out, name) });
    return { ...state, foreground_fraction: await foregroundFraction(page, png) };
  };
  result.live_first = await shot('live_1.png', 0);
  await page.waitForTimeout(args.liveGapMs);
  result.live_second = await shot('live_2.png', result.live_first.version);
  if (!(result.live_second.vertices > result.live_first.vertices)) {
    problems.push(`the live mesh did not grow: ${result.live_first.vertices} -> ${result.live_second.vertices} vertices`);
  }
}

// No two shown object labels overlap (labels.js hides the lesser of overlapping ones).
function checkLabelsApart(a, when, problems) {
  for (let i = 0; i < a.length; ++i)
    for (let j = i + 1; j < a.length; ++j)
      if (a[i].left < a[j].right && a[j].left < a[i].right && a[i].top < a[j].bottom && a[j].top < a[i].bottom)
        problems.push(`${when}: object labels ${i} and ${j} overlap: ${JSON.stringify(a[i])} ${JSON.stringify(a[j])}`);
}

// The checks of a finished output folder (`semap view DIR`).
async function folderChecks(page, args, result, problems) {
  // 1. The page as a person sees it.
  await page.screenshot({ path: path.join(args.out, 'viewer.png') });
  const labels = await page.evaluate(() => window.semapViewer.labelStats());
  result.labels_shown = labels.shown;
  result.labels_hidden = labels.hidden;
  checkLabelsApart(labels.rects, 'first view', problems);

  // 2. The canvas alone: the mesh must cover a real share of it.
  await page.evaluate(() => { document.body.classList.add('hide-ui'); window.semapViewer.render(); });
  const canvasPng = await page.screenshot({ path: path.join(args.out, 'canvas.png') });
  result.foreground_fraction = await foregroundFraction(page, canvasPng);
  if (!(result.foreground_fraction > args.minFraction)) {
    problems.push(`only ${(100 * result.foreground_fraction).toFixed(2)}% of the canvas differs from the background (need > ${(100 * args.minFraction).toFixed(2)}%)`);
  }

  await layerChecks(page, args, result, problems);
  await page.evaluate(() => { document.body.classList.add('hide-ui'); window.semapViewer.render(); });

  // 3. Every class off: the triangles disappear (boxes and trajectory remain, thin lines; the
  // grid and graph layers are switched off for this shot).
  await page.evaluate(() => {
    for (const name of ['grid', 'graph']) window.semapViewer.setLayer(name, false);
    window.semapViewer.setAllClasses(false);
    window.semapViewer.render();
  });
  const hiddenPng = await page.screenshot({ path: path.join(args.out, 'classes_off.png') });
  result.foreground_fraction_classes_off = await foregroundFraction(page, hiddenPng);
  result.visible_triangles_classes_off = await page.evaluate(() => window.semapViewer.visibleTriangleCount());
  if (result.visible_triangles_classes_off !== 0) problems.push('triangles remain with every class switched off');
  if (!(result.foreground_fraction_classes_off < 0.5 * result.foreground_fraction)) {
    problems.push(`class toggles do not hide the mesh (${result.foreground_fraction_classes_off} vs ${result.foreground_fraction})`);
  }
  await page.evaluate(() => {
    for (const name of ['grid', 'graph']) window.semapViewer.setLayer(name, true);
    window.semapViewer.setAllClasses(true);
    document.body.classList.remove('hide-ui');
    window.semapViewer.render();
  });

  // 4. Click the first object's box: its panel shows the distribution and point count.
  if (result.objects > 0) {
    const target = await page.evaluate(() => window.semapViewer.objectScreenPosition(0));
    await page.mouse.click(target.x, target.y);
    await page.waitForTimeout(200);
    const panel = await page.evaluate(() => {
      const info = document.getElementById('object-info');
      return { hidden: info.hidden, text: info.innerText };
    });
    result.object_panel = panel.text;
    if (panel.hidden || !/point count/.test(panel.text) || !/class distribution/.test(panel.text)) {
      problems.push(`clicking object ${target.id} did not open its panel: ${JSON.stringify(panel)}`);
    }
    await page.screenshot({ path: path.join(args.out, 'object_panel.png') });

    // 5. Zoomed in on the first object (wheel events on the canvas): labels still apart, and
    // those hidden for overlapping come back as the objects spread (labels_zoomed.png).
    await page.evaluate(async ({ x, y }) => {
      const canvas = document.querySelector('#viewport canvas');
      for (let k = 0; k < 8; ++k) canvas.dispatchEvent(new WheelEvent('wheel', { deltaY: -200, clientX: x, clientY: y, bubbles: true, cancelable: true }));
      window.semapViewer.render();
    }, target);
    const zoomed = await page.evaluate(() => window.semapViewer.labelStats());
    result.labels_hidden_zoomed = zoomed.hidden;
    checkLabelsApart(zoomed.rects, 'zoomed in', problems);
    await page.screenshot({ path: path.join(args.out, 'labels_zoomed.png') });
  }
}

async function main() {
  const args = parseArgs(process.argv);
  fs.mkdirSync(args.out, { recursive: true });
  const problems = [];
  const consoleErrors = [];
  const result = { url: args.url };

  const profile = fs.mkdtempSync(path.join(os.tmpdir(), 'semap-chromium-'));
  let context;
  try {
    context = await chromium.launchPersistentContext(profile, {
      executablePath: args.chromium,
      headless: true,
      viewport: { width: 1280, height: 800 },
      deviceScaleFactor: 1,
      args: [
        '--no-sandbox', '--disable-gpu', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
        '--disable-quic', '--no-first-run', '--disable-background-networking',
        '--disable-component-update', '--disable-sync', '--disable-dev-shm-usage',
      ],
    });
  } catch (error) {
    console.log(`cannot start chromium (${args.chromium}): ${error.message}`);
    fs.rmSync(profile, { recursive: true, force: true });
    process.exit(2);
  }

  try {
    const page = context.pages()[0] || await context.newPage();
    page.on('console', (message) => {
      if (message.type() === 'error') consoleErrors.push(`console: ${message.text()}`);
    });
    page.on('pageerror', (error) => consoleErrors.push(`page error: ${error.message}`));
    page.on('requestfailed', (request) => consoleErrors.push(`request failed: ${request.url()} ${request.failure()?.errorText}`));
    page.on('response', (response) => {
      if (response.status() >= 400) consoleErrors.push(`HTTP ${response.status()}: ${response.url()}`);
    });

    await page.goto(args.url, { waitUntil: 'load', timeout: args.timeoutMs });
    await page.waitForFunction(() => window.semapViewer && window.semapViewer.ready, null, { timeout: args.timeoutMs });
    result.messages = await page.evaluate(() => window.semapViewer.messages);
    result.objects = await page.evaluate(() => window.semapViewer.objectCount());
    result.visible_triangles = await page.evaluate(() => window.semapViewer.visibleTriangleCount());
    if (args.liveGapMs > 0) await liveCheck(page, args, result, problems);
    else await folderChecks(page, args, result, problems);

  } catch (error) {
    problems.push(`viewer check failed: ${error.message}`);
  } finally {
    await context.close();
    fs.rmSync(profile, { recursive: true, force: true });
  }

  result.console_errors = consoleErrors;
  if (consoleErrors.length > 0) problems.push(`${consoleErrors.length} console error(s): ${consoleErrors.join(' | ')}`);
  result.problems = problems;
  fs.writeFileSync(path.join(args.out, 'result.json'), JSON.stringify(result, null, 2));
  console.log(JSON.stringify(result, null, 2));
  process.exit(problems.length === 0 ? 0 : 1);
}

main().catch((error) => {
  console.log(`screenshot.mjs: ${error.stack || error}`);
  process.exit(2);
});
