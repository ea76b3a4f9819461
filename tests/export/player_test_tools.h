#pragma once
// Test helpers for the web player and the glTF files (tests/export/ and the export command's
// end-to-end test): finding node, the npm packages and Debian's chromium, running the node
// scripts of tests/export/, and comparing a screenshot with confluent's render.

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "core/image.h"
#include "core/video_writer.h"
#include "tests/support/test_support.h"

namespace confluent::testing {

// The checkout's root, from this file's path (tests/export/).
inline std::string SourceRoot() {
  std::string path = __FILE__;
  for (int i = 0; i < 3; ++i) path = path.substr(0, path.find_last_of('/'));
  return path;
}

// export/player/node_modules of the checkout ("" when `package` is not installed there).
inline std::string PlayerNodeModules(const std::string& package) {
  const std::string modules = SourceRoot() + "/export/player/node_modules";
  const std::string probe = modules + "/" + package + "/package.json";
  return std::system(("test -f '" + probe + "'").c_str()) == 0 ? modules : "";
}

// Whether `node` runs.
inline bool NodeAvailable() { return std::system("node --version >/dev/null 2>&1") == 0; }


// What the Chromium tests need: node, playwright-core from export/player's npm packages, Debian's
// chromium ($CONFLUENT_CHROMIUM overrides) and ffmpeg; `missing` says what is not there.
struct Browser {
  std::string chromium;
  std::string modules;
  std::string missing;
};

inline Browser FindBrowser() {
  Browser browser;
  const char* chromium_env = std::getenv("CONFLUENT_CHROMIUM");
  browser.chromium = chromium_env ? chromium_env : "/usr/bin/chromium";
  browser.modules = PlayerNodeModules("playwright-core");
  if (!NodeAvailable() || browser.modules.empty() ||
      std::system(("test -x '" + browser.chromium + "'").c_str()) != 0) {
    browser.missing = "needs node, export/player/node_modules/playwright-core (npm ci --prefix export/player) and " +
                      browser.chromium + " (Debian's chromium; $CONFLUENT_CHROMIUM overrides)";
  } else if (!FfmpegAvailable()) {
    browser.missing = "ffmpeg is missing (the atlas video)";
  }
  return browser;
}

// Runs tests/export/<script> with node and returns its output (stdout and stderr).
inline std::string RunNodeScript(const std::string& script, const std::vector<std::string>& args) {
  std::string command = "node '" + SourceRoot() + "/tests/export/" + script + "'";
  for (const std::string& arg : args) command += " '" + arg + "'";
  return CaptureOutput(command + " 2>&1");
}

// The Khronos validator's report on a .glb ("" when node or gltf-validator is missing), ending in
// "exit=<status>".
inline std::string ValidateGltf(const std::string& path) {
  const std::string modules = PlayerNodeModules("gltf-validator");
  if (!NodeAvailable() || modules.empty()) return "";
  return CaptureOutput("node '" + SourceRoot() + "/tests/export/gltf_validate.cjs' '" + modules + "' '" + path +
                       "' 2>&1; echo exit=$?");
}

// Pixels brighter than a black background.
inline Image Silhouette(const Image& image) {
  Image mask(image.width, image.height, 1);
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      int brightest = 0;
      for (int c = 0; c < 3; ++c) brightest = std::max<int>(brightest, image.at<std::uint8_t>(x, y, c));
      mask.at<std::uint8_t>(x, y) = brightest > 12 ? 255 : 0;
    }
  }
  return mask;
}

// IoU of two masks; `intersection` receives where both are set.
inline double Iou(const Image& a, const Image& b, Image* intersection) {
  *intersection = Image(a.width, a.height, 1);
  long both = 0, either = 0;
  for (std::size_t i = 0; i < a.data.size(); ++i) {
    const bool in_a = a.data[i] != 0, in_b = b.data[i] != 0;
    both += in_a && in_b;
    either += in_a || in_b;
    intersection->data[i] = in_a && in_b ? 255 : 0;
  }
  return either ? static_cast<double>(both) / either : 0.0;
}

}  // namespace confluent::testing
