// Plays confluent's web player (no camera query: the interactive page) in Debian's headless
// Chromium and reports, as JSON on stdout: the mesh frames seen while playing, then the mesh
// frame and video time after pressing pause, and after moving the timeline to frame <seek>.
// Exits 1 when the page failed.
//   node player_interaction.cjs <node_modules> <chromium> <served folder> <page path> <seek> [timeout_s]
const { runPage } = require('./player_browser.cjs');
const [modules, chromium, root, page_path, seek, timeout_s] = process.argv.slice(2);

const state = () => ({ frame: window.playerFrame, fps: window.playerFps, time: document.getElementById('atlas').currentTime,
                       paused: document.getElementById('atlas').paused, error: window.playerError });

runPage({ modules, chromium, root, page_path, viewport: { width: 480, height: 360 }, timeout_s }, async (page, report) => {
  const seen = new Set();
  for (let i = 0; i < 60; ++i) {
    seen.add(await page.evaluate(() => window.playerFrame));
    await page.waitForTimeout(20);
  }
  report.frames_seen_playing = [...seen].sort((a, b) => a - b);
  await page.click('#play');
  await page.waitForTimeout(500);
  report.after_pause = await page.evaluate(state);
  await page.evaluate((k) => {
    const timeline = document.getElementById('timeline');
    timeline.value = String(k);
    timeline.dispatchEvent(new Event('input'));
  }, Number(seek));
  await page.waitForTimeout(500);
  report.after_seek = await page.evaluate(state);
  report.ok = !report.after_seek.error && !report.page_error;
}).then((report) => {
  console.log(JSON.stringify(report, null, 1));
  process.exit(report.ok && !report.error ? 0 : 1);
});
