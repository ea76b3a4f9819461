// Opens confluent's web player in Debian's headless Chromium from a local web server, waits for
// window.playerReady and saves a screenshot of the page (the fixed-camera query of
// export/player/player.js). Prints a JSON report on stdout; exits 1 when the page failed.
//   node player_screenshot.cjs <node_modules> <chromium> <served folder> <page path + query>
//        <width> <height> <screenshot.png> [timeout_s]
const { runPage } = require('./player_browser.cjs');
const [modules, chromium, root, page_path, width, height, output, timeout_s] = process.argv.slice(2);
const viewport = { width: Number(width), height: Number(height) };

runPage({ modules, chromium, root, page_path, viewport, timeout_s }, async (page, report) => {
  Object.assign(report, await page.evaluate(() => ({
    ready: window.playerReady, error: window.playerError, frame: window.playerFrame,
    video_error: window.playerVideoError || null,
    h264: document.createElement('video').canPlayType('video/mp4; codecs="avc1.42E01E"'),
    vp9: document.createElement('video').canPlayType('video/webm; codecs="vp9"') })));
  if (report.ready) await page.screenshot({ path: output, clip: { x: 0, y: 0, ...viewport } });
}).then((report) => {
  console.log(JSON.stringify(report, null, 1));
  process.exit(report.ready && !report.error ? 0 : 1);
});
