// Opens confluent's web player in Debian's headless Chromium (playwright-core, never a
// downloaded browser) from a local web server, waits for window.playerReady and saves a
// screenshot of the page. Playwright gives Chromium a fresh temporary profile (user data dir). Prints a JSON report on stdout; exits 1 when the page failed.
//   node player_screenshot.cjs <node_modules> <chromium> <served folder> <page path + query>
//        <width> <height> <screenshot.png> [timeout_s]
const fs = require('fs');
const http = require('http');
const path = require('path');
const [modules, chromium, root, page_path, width, height, output, timeout_s] = process.argv.slice(2);
const { chromium: browserType } = require(path.join(modules, 'playwright-core'));

const types = { '.html': 'text/html', '.js': 'text/javascript', '.mjs': 'text/javascript', '.json': 'application/json',
                '.glb': 'model/gltf-binary', '.mp4': 'video/mp4', '.webm': 'video/webm', '.png': 'image/png' };

// A static file server with byte ranges (Chromium seeks in videos with Range requests).
function serve(request, response) {
  const file = path.join(root, decodeURIComponent(new URL(request.url, 'http://x').pathname));
  if (!file.startsWith(path.resolve(root)) || !fs.existsSync(file) || !fs.statSync(file).isFile()) {
    response.writeHead(404);
    response.end();
    return;
  }
  const size = fs.statSync(file).size;
  const headers = { 'Content-Type': types[path.extname(file)] || 'application/octet-stream', 'Accept-Ranges': 'bytes' };
  const range = /bytes=(\d*)-(\d*)/.exec(request.headers.range || '');
  if (range) {
    const start = range[1] ? Number(range[1]) : 0;
    const end = range[2] ? Math.min(Number(range[2]), size - 1) : size - 1;
    response.writeHead(206, { ...headers, 'Content-Range': `bytes ${start}-${end}/${size}`, 'Content-Length': end - start + 1 });
    fs.createReadStream(file, { start, end }).pipe(response);
  } else {
    response.writeHead(200, { ...headers, 'Content-Length': size });
    fs.createReadStream(file).pipe(response);
  }
}

(async () => {
  const server = http.createServer(serve);
  await new Promise((resolve) => server.listen(0, '127.0.0.1', resolve));
  const url = `http://127.0.0.1:${server.address().port}/${page_path}`;
  const log = [];
  let browser = null;
  let page = null;
  let report = { url };
  try {
    browser = await browserType.launch({
      executablePath: chromium,
      headless: true,
      args: ['--no-sandbox', '--no-first-run', '--disable-background-networking', '--disable-component-update',
             '--disable-sync', '--disable-quic', '--use-angle=swiftshader',
             '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist', '--autoplay-policy=no-user-gesture-required'],
    });
    const context = await browser.newContext({ viewport: { width: Number(width), height: Number(height) }, deviceScaleFactor: 1 });
    page = await context.newPage();
    page.on('console', (message) => log.push(`${message.type()}: ${message.text()}`));
    page.on('pageerror', (error) => log.push(`pageerror: ${error.message}`));
    await page.goto(url);
    await page.waitForFunction(() => window.playerReady || window.playerError, null,
                               { timeout: 1000 * Number(timeout_s || 60) });
    const state = await page.evaluate(() => ({ ready: window.playerReady, error: window.playerError,
                                               frame: window.playerFrame, video_error: window.playerVideoError || null,
                                               h264: document.createElement('video').canPlayType('video/mp4; codecs="avc1.42E01E"'),
                                               vp9: document.createElement('video').canPlayType('video/webm; codecs="vp9"') }));
    report = { ...report, ...state };
    if (state.ready) await page.screenshot({ path: output, clip: { x: 0, y: 0, width: Number(width), height: Number(height) } });
  } catch (error) {
    report.error = String(error);
    if (page) {  // where it stopped
      report.diagnosis = await page.evaluate(() => {
        const video = document.getElementById('atlas');
        return { status: document.getElementById('status')?.textContent, video_ready_state: video?.readyState,
                 video_error: video?.error?.message || null, video_time: video?.currentTime };
      }).catch((e) => String(e));
    }
  } finally {
    if (browser) await browser.close();
    server.close();
  }
  report.console = log;
  console.log(JSON.stringify(report, null, 1));
  process.exit(report.ready && !report.error ? 0 : 1);
})();
