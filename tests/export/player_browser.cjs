// Shared by the player's Chromium scripts: a static file server for a folder (with byte ranges,
// which Chromium's video seeking uses) and Debian's headless Chromium through playwright-core
// (never a downloaded browser; playwright gives it a fresh temporary profile).
const fs = require('fs');
const http = require('http');
const path = require('path');

const types = { '.html': 'text/html', '.js': 'text/javascript', '.mjs': 'text/javascript', '.json': 'application/json',
                '.glb': 'model/gltf-binary', '.mp4': 'video/mp4', '.webm': 'video/webm', '.png': 'image/png' };

// Serves `root` on 127.0.0.1 at a free port; resolves to the server (server.address().port).
async function serveFolder(root) {
  const server = http.createServer((request, response) => {
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
  });
  await new Promise((resolve) => server.listen(0, '127.0.0.1', resolve));
  return server;
}

// Starts headless Chromium at `executable` with WebGL on SwiftShader (no GPU needed).
function launchChromium(modules, executable) {
  const { chromium } = require(path.join(modules, 'playwright-core'));
  return chromium.launch({
    executablePath: executable,
    headless: true,
    args: ['--no-sandbox', '--no-first-run', '--disable-background-networking', '--disable-component-update',
           '--disable-sync', '--disable-quic', '--disable-dev-shm-usage', '--use-angle=swiftshader',
           '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist', '--autoplay-policy=no-user-gesture-required'],
  });
}

// Where a page that never got ready stopped.
function diagnose(page) {
  return page.evaluate(() => {
    const video = document.getElementById('atlas');
    return { status: document.getElementById('status')?.textContent, error: window.playerError,
             video_ready_state: video?.readyState, video_error: video?.error?.message || null,
             video_time: video?.currentTime };
  }).catch((e) => String(e));
}

// Serves `root`, opens `page_path` in Chromium at `viewport`, waits for window.playerReady (or
// playerError), then awaits `body(page, report)`. Resolves to `report` ({url, console, ...};
// report.error when something threw, with report.diagnosis); closes the browser and server.
async function runPage({ modules, chromium, root, page_path, viewport, timeout_s }, body) {
  const server = await serveFolder(root);
  const report = { url: `http://127.0.0.1:${server.address().port}/${page_path}`, console: [] };
  let browser = null;
  let page = null;
  try {
    browser = await launchChromium(modules, chromium);
    page = await (await browser.newContext({ viewport, deviceScaleFactor: 1 })).newPage();
    page.on('console', (message) => report.console.push(`${message.type()}: ${message.text()}`));
    page.on('pageerror', (error) => { report.page_error = error.message; });
    await page.goto(report.url);
    await page.waitForFunction(() => window.playerReady || window.playerError, null,
                               { timeout: 1000 * Number(timeout_s || 60) });
    await body(page, report);
  } catch (error) {
    report.error = String(error);
    if (page) report.diagnosis = await diagnose(page);
  } finally {
    if (browser) await browser.close();
    server.close();
  }
  return report;
}

module.exports = { runPage };
