// Opens confluent's web player in Debian's headless Chromium from a local web server, waits for
// window.playerReady and saves a screenshot of the page (the fixed-camera query of
// export/player/player.js). Prints a JSON report on stdout; exits 1 when the page failed.
//   node player_screenshot.cjs <node_modules> <chromium> <served folder> <page path + query>
//        <width> <height> <screenshot.png> [timeout_s]
const { serveFolder, launchChromium, diagnose } = require('./player_browser.cjs');
const [modules, chromium, root, page_path, width, height, output, timeout_s] = process.argv.slice(2);

(async () => {
  const server = await serveFolder(root);
  const url = `http://127.0.0.1:${server.address().port}/${page_path}`;
  const log = [];
  let browser = null;
  let page = null;
  let report = { url };
  try {
    browser = await launchChromium(modules, chromium);
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
    if (page) report.diagnosis = await diagnose(page);
  } finally {
    if (browser) await browser.close();
    server.close();
  }
  report.console = log;
  console.log(JSON.stringify(report, null, 1));
  process.exit(report.ready && !report.error ? 0 : 1);
})();
