// Renders a gcr lightmap .glb in three.js in headless Chromium, saves what the viewer shows
// (PNG) and compares its linear radiance with gcr's per-pixel EXR of the same camera.
//
//   npm ci --prefix xtask/js/lightmap-view        # three.js and playwright-core, pinned
//   gcr solve cornell-box --lightmap cb.glb --image cb.exr --image-mode pixel
//   node xtask/js/lightmap-view/view.mjs cb.glb view.png --reference cb.exr \
//       --eye 0.278,0.273,-0.8 --target 0.278,0.273,0 --fov 39.3076 [--size 512x512] [--exposure E]
//       [--dump PREFIX]   (both luminance images as float32, PREFIX.three.f32 and PREFIX.gcr.f32)
//
// The camera is the one gcr prints for the image (Mitsuba's look_at convention, which is
// three.js' lookAt: both look down the view direction with the given up). Needs Chromium
// (Debian's `chromium`; CHROMIUM=path to use another). Without it the script says so and exits 0.
import http from 'node:http';
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
const args = process.argv.slice(2);
const opt = (name, dflt) => {
  const i = args.indexOf(`--${name}`);
  return i >= 0 ? args[i + 1] : dflt;
};
const [glb, png] = args;
if (!glb || !png || glb.startsWith('--')) {
  console.error('usage: view.mjs SCENE.glb OUT.png --eye X,Y,Z --target X,Y,Z [--up 0,1,0] [--fov 40] [--size 512x512] [--exposure E] [--reference PIXELS.exr]');
  process.exit(2);
}
const chromium = process.env.CHROMIUM || '/usr/bin/chromium';
if (!fs.existsSync(chromium)) {
  console.log(`skipped: no Chromium at ${chromium} (apt-get install chromium, or set CHROMIUM)`);
  process.exit(0);
}
let playwright;
try {
  playwright = await import('playwright-core');
} catch {
  console.log(`skipped: playwright-core is not installed (npm ci --prefix ${path.relative(process.cwd(), here)})`);
  process.exit(0);
}
const reference = opt('reference');
const view = {
  eye: opt('eye'), target: opt('target'), up: opt('up', '0,1,0'), fov: opt('fov', '40'),
  size: opt('size', '512x512'), exposure: opt('exposure', ''),
};
if (!view.eye || !view.target) {
  console.error('--eye and --target are required (gcr prints them for every image)');
  process.exit(2);
}

// Exposure: given, or as gcr chooses it (the 95th percentile of the lit pixels' luminance → 0.8),
// taken from the float render below on a first pass.
const files = {
  '/': [path.join(here, 'page.html'), 'text/html'],
  '/view-page.js': [path.join(here, 'view-page.js'), 'text/javascript'],
  '/scene.glb': [glb, 'model/gltf-binary'],
  '/reference.exr': [reference, 'application/octet-stream'],
};
const three = path.join(here, 'node_modules', 'three');
const server = http.createServer((req, res) => {
  const url = new URL(req.url, 'http://x');
  let file = files[url.pathname];
  if (!file && url.pathname.startsWith('/three/')) {
    const p = path.normalize(path.join(three, url.pathname.slice('/three/'.length)));
    if (p.startsWith(three)) file = [p, 'text/javascript'];
  }
  if (!file || !file[0] || !fs.existsSync(file[0])) { res.writeHead(url.pathname === '/favicon.ico' ? 204 : 404); res.end(); return; }
  res.writeHead(200, { 'content-type': file[1] });
  fs.createReadStream(file[0]).pipe(res);
});
await new Promise((ok) => server.listen(0, '127.0.0.1', ok));
const port = server.address().port;

const browser = await playwright.chromium.launch({
  executablePath: chromium,
  args: ['--headless', '--no-sandbox', '--disable-quic', '--no-first-run', '--disable-background-networking',
    '--disable-component-update', '--disable-sync', '--use-angle=swiftshader', '--enable-unsafe-swiftshader'],
});
try {
  const [w, h] = view.size.split('x').map(Number);
  const page = await browser.newPage({ viewport: { width: w, height: h }, deviceScaleFactor: 1 });
  page.on('console', (m) => { if (m.type() === 'error') console.error(`page: ${m.text()}`); });
  const render = async (exposure) => {
    const q = new URLSearchParams({ ...view, exposure: String(exposure), reference: reference ? '1' : '' });
    await page.goto(`http://127.0.0.1:${port}/?${q}`);
    await page.waitForFunction(() => window.result !== undefined, null, { timeout: 120000 });
    const r = await page.evaluate(() => window.result);
    if (r.error) throw new Error(r.error);
    return r;
  };
  let r = await render(view.exposure || 1);
  let exposure = Number(view.exposure);
  if (!view.exposure) {
    const lit = r.compare ? r.compare.three.filter((v) => v > 0).sort((a, b) => a - b) : [];
    exposure = lit.length ? 0.8 / lit[Math.floor(0.95 * (lit.length - 1))] : 1;
    r = await render(exposure);
  }
  const canvas = await page.$('canvas');
  await canvas.screenshot({ path: png });
  console.log(`${png}: ${w}x${h}, ${r.lightmapped} of ${r.meshes} meshes lightmapped, exposure ${exposure.toPrecision(4)}`);
  if (r.compare) report(r.compare.three, r.compare.gcr, w, h);
  if (r.compare && opt('dump')) {
    // Both luminance images as little-endian float32, rows bottom-up, for a closer look.
    fs.writeFileSync(`${opt('dump')}.three.f32`, Buffer.from(new Float32Array(r.compare.three).buffer));
    fs.writeFileSync(`${opt('dump')}.gcr.f32`, Buffer.from(new Float32Array(r.compare.gcr).buffer));
  }
} finally {
  await browser.close();
  server.close();
}

// The difference where the surface is smooth: no geometric or shadow edge in the pixel's 3×3
// neighbourhood (rasterization and ray casting cover edge pixels differently) and no emitter (a
// light's own pixels agree exactly and would swamp the sums). As the bake's error is defined
// (‖σ‖₂/‖B‖₂ over its texels), ‖three − gcr‖₂/‖gcr‖₂ compares with √(e_bake² + e_image²) when
// both are unbiased; the sums' ratio is the bias. Then per face-sized 9×9 blocks (noise mostly
// averaged away).
function report(a, b, w, h) {
  const lit = b.filter((v) => v > 0);
  const median = [...lit].sort((x, y) => x - y)[Math.floor(lit.length / 2)] || 0;
  const smooth = new Uint8Array(w * h);
  for (let y = 1; y < h - 1; y++) {
    for (let x = 1; x < w - 1; x++) {
      let lo = Infinity, hi = 0;
      for (let dy = -1; dy <= 1; dy++) for (let dx = -1; dx <= 1; dx++) {
        const i = (y + dy) * w + x + dx;
        lo = Math.min(lo, a[i], b[i]); hi = Math.max(hi, a[i], b[i]);
      }
      smooth[y * w + x] = lo > 0 && hi / lo < 1.5 && hi < 10 * median ? 1 : 0;
    }
  }
  let n = 0, sa = 0, sb = 0, d2 = 0, b2 = 0;
  for (let i = 0; i < w * h; i++) {
    if (!smooth[i]) continue;
    n += 1; sa += a[i]; sb += b[i];
    d2 += (a[i] - b[i]) ** 2; b2 += b[i] ** 2;
  }
  const k = 4, local = [];
  for (let y = k; y < h - k; y += 2 * k + 1) {
    for (let x = k; x < w - k; x += 2 * k + 1) {
      let ok = true, la = 0, lb = 0;
      for (let dy = -k; dy <= k && ok; dy++) for (let dx = -k; dx <= k; dx++) {
        const i = (y + dy) * w + x + dx;
        if (!smooth[i]) { ok = false; break; }
        la += a[i]; lb += b[i];
      }
      if (ok) local.push(Math.abs(la / lb - 1));
    }
  }
  local.sort((x, y) => x - y);
  const pct = (v, p) => (100 * v[Math.floor(p * (v.length - 1))]).toFixed(2);
  console.log(`compared ${n} pixels (${(100 * n / lit.length).toFixed(1)} % of the ${lit.length} lit; edges and emitters left out)`);
  console.log(`  bias (sum three / sum gcr - 1): ${(100 * (sa / sb - 1)).toFixed(2)} %`);
  console.log(`  difference |three - gcr| / |gcr|: ${(100 * Math.sqrt(d2 / b2)).toFixed(2)} % (compare sqrt(e_bake^2 + e_image^2))`);
  console.log(`  9x9 blocks (${local.length}): |ratio - 1| median ${pct(local, 0.5)} %, 95th percentile ${pct(local, 0.95)} %`);
}
