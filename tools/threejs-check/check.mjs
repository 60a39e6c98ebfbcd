#!/usr/bin/env node
// Plays GLBs morphkit writes in three.js (GLTFLoader + AnimationMixer) in headless Chromium and
// compares them with the OBJ frames they were made from.
//
// Usage: node check.mjs [--shots DIR] [--tol REL] [--bake WEIGHTS.csv] FILE.glb FRAMES_DIR [...]
//
// With --bake, each GLB is a baked rig (`morphkit bake`) and is played not by its clip but by
// the slider weights of each CSV row (header: the sliders' names), through the JavaScript
// evaluation in docs/bake.md itself (its ```js block, loaded as a module), frame k for row k.
//
// For each pair: serves the GLB, three.js (from node_modules) and the OBJ frames (frame_*.obj,
// sorted) on localhost; loads the GLB with GLTFLoader; steps the AnimationMixer to every key;
// computes the one visible mesh's morphed positions from its morph attributes and influences;
// and checks them against the frames (max error ≤ REL × bounding-box diagonal, default 1e-6).
// It renders the first and the last key on the GPU (SwiftShader under --disable-gpu) and checks
// that both are not blank and that they differ, and that WebGL logged no error (a mesh with more
// morph targets than the GPU holds logs INVALID_VALUE and stays at its base). Screenshots go to
// DIR (default: none). Prints one JSON line per file; exits 1 on any failure, 2 on bad usage
// or when Chromium is missing. Chromium: $CHROMIUM or /usr/bin/chromium (Debian's `chromium`).
import http from 'node:http';
import { readFile, readdir, mkdtemp, rm, mkdir } from 'node:fs/promises';
import { existsSync } from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';

const here = path.dirname(fileURLToPath(import.meta.url));
const args = process.argv.slice(2);
let shots = null;
let tol = 1e-6;
let bake = null;
const pairs = [];
for (let i = 0; i < args.length; i++) {
  if (args[i] === '--shots') shots = args[++i];
  else if (args[i] === '--tol') tol = Number(args[++i]);
  else if (args[i] === '--bake') bake = args[++i];
  else pairs.push(args[i]);
}
if (pairs.length === 0 || pairs.length % 2 !== 0) {
  console.error('usage: node check.mjs [--shots DIR] [--tol REL] FILE.glb FRAMES_DIR ...');
  process.exit(2);
}
const exe = process.env.CHROMIUM || '/usr/bin/chromium';
if (!existsSync(exe)) {
  console.error(`check.mjs: no Chromium at ${exe}; install Debian's chromium (apt-get install -y chromium) or set CHROMIUM`);
  process.exit(2);
}

/** The positions of an OBJ file's `v` lines. */
function objPositions(text) {
  const out = [];
  for (const line of text.split('\n')) {
    if (line.startsWith('v ')) {
      const [, x, y, z] = line.trim().split(/\s+/);
      out.push(Number(x), Number(y), Number(z));
    }
  }
  return out;
}

const files = new Map();
if (bake) {
  // The slider rows, and docs/bake.md's evaluation as a module.
  const rows = (await readFile(bake, 'utf8')).trim().split('\n').slice(1)
    .map((l) => l.split(',').map(Number));
  files.set('/bake-rows.json', Buffer.from(JSON.stringify(rows)));
  const doc = await readFile(path.join(here, '..', '..', 'docs', 'bake.md'), 'utf8');
  const js = /```js\n([\s\S]*?)```/.exec(doc);
  if (!js) {
    console.error('check.mjs: docs/bake.md has no ```js block');
    process.exit(2);
  }
  files.set('/bake.js', Buffer.from(`${js[1]}\nexport { playBake };\n`));
}
for (let i = 0; i < pairs.length; i += 2) {
  const id = String(i / 2);
  const dir = pairs[i + 1];
  const names = (await readdir(dir)).filter((n) => /^frame_\d+\.obj$/.test(n)).sort();
  if (names.length === 0) {
    console.error(`${dir}: no frame_*.obj files`);
    process.exit(2);
  }
  const all = [];
  for (const n of names) all.push(...objPositions(await readFile(path.join(dir, n), 'utf8')));
  files.set(`/files/${id}.glb`, await readFile(pairs[i]));
  files.set(`/files/${id}.expected`, Buffer.from(new Float64Array(all).buffer));
}

const types = { '.js': 'text/javascript', '.html': 'text/html', '.glb': 'model/gltf-binary' };
const server = http.createServer(async (req, res) => {
  const url = decodeURIComponent(new URL(req.url, 'http://localhost').pathname);
  try {
    let body;
    if (url === '/favicon.ico') { res.writeHead(204); res.end(); return; }
    if (url === '/') body = await readFile(path.join(here, 'page.html'));
    else if (files.has(url)) body = files.get(url);
    else if (url.startsWith('/three/') && !url.includes('..')) body = await readFile(path.join(here, 'node_modules', url));
    else throw new Error('not found');
    res.writeHead(200, { 'content-type': types[path.extname(url)] || (url === '/' ? 'text/html' : 'application/octet-stream') });
    res.end(body);
  } catch {
    res.writeHead(404);
    res.end();
  }
});
await new Promise((r) => server.listen(0, '127.0.0.1', r));
const port = server.address().port;

const profile = await mkdtemp(path.join(os.tmpdir(), 'morphkit-threejs-'));
const width = 480, height = 360;
let failed = false;
const context = await chromium.launchPersistentContext(profile, {
  executablePath: exe,
  headless: true,
  args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
    '--disable-background-networking', '--disable-component-update', '--disable-sync',
    '--use-angle=swiftshader', '--enable-unsafe-swiftshader'],
  viewport: { width, height },
});
try {
  for (let i = 0; i < pairs.length; i += 2) {
    const id = String(i / 2);
    const page = await context.newPage();
    const glErrors = [];
    page.on('console', (m) => {
      const t = m.text();
      if (m.type() === 'error' || /GL_INVALID|INVALID_VALUE|WebGL: /.test(t)) glErrors.push(t);
    });
    page.on('pageerror', (e) => glErrors.push(String(e)));
    await page.goto(`http://127.0.0.1:${port}/`);
    await page.waitForFunction(() => window.ready === true);
    const r = await page.evaluate(([id, w, h, b]) => window.runCheck(id, w, h, b), [id, width, height, bake !== null]);
    const problems = [];
    if (r.frames !== r.keys) problems.push(`${r.keys} keys for ${r.frames} frames`);
    if (!(r.relErr <= tol)) problems.push(`positions differ by ${r.relErr.toExponential(2)} of the diagonal (frame ${r.worstFrame})`);
    if (r.visibleErrors.length) problems.push(r.visibleErrors.join('; '));
    if (r.firstPixels < 100 || r.lastPixels < 100) problems.push(`blank render (${r.firstPixels} / ${r.lastPixels} pixels drawn)`);
    if (r.differingPixels < 100) problems.push(`first and last frames render the same (${r.differingPixels} pixels differ)`);
    if (r.glError !== 0) problems.push(`WebGL error ${r.glError}`);
    if (glErrors.length) problems.push(`console: ${glErrors.slice(0, 3).join(' | ')}`);
    if (shots) {
      await mkdir(shots, { recursive: true });
      const stem = path.basename(pairs[i], '.glb');
      await page.evaluate(() => window.show(0));
      await page.screenshot({ path: path.join(shots, `${stem}-first.png`) });
      await page.evaluate(() => window.show(-1));
      await page.screenshot({ path: path.join(shots, `${stem}-last.png`) });
    }
    console.log(JSON.stringify({ file: pairs[i], ok: problems.length === 0, problems, ...r }));
    if (problems.length) failed = true;
    await page.close();
  }
} finally {
  await context.close();
  server.close();
  await rm(profile, { recursive: true, force: true });
}
process.exit(failed ? 1 : 0);
