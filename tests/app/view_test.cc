// `confluent view`: screenshots under a private Xvfb server checked against the known geometry
// of a moving red box, and the viewer's errors (not a run folder, no display, no frames).

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "calib/camera.h"
#include "calib/easymocap_io.h"
#include "core/atomic_file.h"
#include "core/image.h"
#include "core/image_io.h"
#include "core/mesh_io.h"
#include "core/mesh_ops.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {
namespace fs = std::filesystem;

// Under AddressSanitizer: GLFW loads the GL driver with dlopen and unloads it when the viewer
// ends, and LeakSanitizer then reports what the driver keeps in its globals as leaked from an
// "<unknown module>" (it cannot be suppressed by name). Preloaded, the driver stays loaded and its
// globals keep that memory reachable. Empty otherwise.
std::string KeepGlDriverLoaded() {
#if defined(__has_feature)
#if __has_feature(address_sanitizer)
  for (const char* driver : {"/usr/lib/x86_64-linux-gnu/dri/swrast_dri.so", "/usr/lib/aarch64-linux-gnu/dri/swrast_dri.so",
                             "/usr/lib64/dri/swrast_dri.so", "/usr/lib/dri/swrast_dri.so"})
    if (fs::exists(driver)) return std::string("export LD_PRELOAD=") + driver + ";";
#endif
#endif
  return "";
}

constexpr double kPi = 3.14159265358979323846;
constexpr int kWidth = 320;
constexpr int kHeight = 240;
constexpr double kShiftPerFrameM = 0.25;  // the box moves along +x by this much per frame

// The box of `frame`: 0.4 m wide, centred at (shift, 0, 1).
Mesh RedBox(int frame) {
  const Eigen::Vector3d offset(kShiftPerFrameM * frame, 0.0, 0.0);
  Mesh box = SubdivideMidpoint(MakeBox(Eigen::Vector3d(-0.2, -0.2, 0.8) + offset, Eigen::Vector3d(0.2, 0.2, 1.2) + offset));
  box.colors = RowMatrixX3f::Zero(box.num_vertices(), 3);
  box.colors.col(0).setConstant(0.9f);
  return box;
}

// The viewer's documented initial view for the box of frame 0 (see `confluent view --help`).
Camera ExpectedView() {
  const Mesh reference = RedBox(0);
  const Eigen::AlignedBox3d bounds = BoundingBox(reference);
  const double half_fov = 20.0 * kPi / 180.0, elevation = 15.0 * kPi / 180.0;
  const double distance = 1.2 * 0.5 * bounds.diagonal().norm() / std::sin(half_fov);
  const Eigen::Vector3d center =
      bounds.center() + distance * Eigen::Vector3d(0.0, -std::cos(elevation), std::sin(elevation));
  return LookAtCamera("view", center, bounds.center(), kWidth, kHeight, 0.5 * kHeight / std::tan(half_fov));
}

bool IsRed(const Image& image, int x, int y) {
  const int r = image.at<std::uint8_t>(x, y, 0), g = image.at<std::uint8_t>(x, y, 1), b = image.at<std::uint8_t>(x, y, 2);
  return r > 50 && r > 3 * g && r > 3 * b;
}

bool IsBackground(const Image& image, int x, int y) {
  const int r = image.at<std::uint8_t>(x, y, 0), g = image.at<std::uint8_t>(x, y, 1), b = image.at<std::uint8_t>(x, y, 2);
  return r < 60 && std::abs(r - g) < 8 && b < 70;
}

// Pixel of a world point in the expected view, rounded.
Eigen::Vector2i PixelOf(const Eigen::Vector3d& point_in_world) {
  const Eigen::Vector2d pixel = ExpectedView().Project(point_in_world);
  return {static_cast<int>(std::lround(pixel.x())), static_cast<int>(std::lround(pixel.y()))};
}

// The path of an executable on $PATH, or "".
std::string FindProgram(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::string dirs = path != nullptr ? path : "/usr/bin:/bin";
  std::size_t start = 0;
  while (start <= dirs.size()) {
    const std::size_t end = std::min(dirs.find(':', start), dirs.size());
    const fs::path candidate = fs::path(dirs.substr(start, end - start)) / name;
    if (access(candidate.c_str(), X_OK) == 0) return candidate.string();
    start = end + 1;
  }
  return {};
}

// A private Xvfb server on a free display number, for the whole suite.
class ViewCommand : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const std::string xvfb = FindProgram("Xvfb");
    if (xvfb.empty()) return;
    // Xvfb chooses a free display itself and writes its number to the pipe (-displayfd).
    int fds[2];
    if (pipe(fds) != 0) return;
    const std::string fd_text = std::to_string(fds[1]);
    const pid_t pid = fork();
    if (pid == 0) {
      close(fds[0]);
      const int null_fd = open("/dev/null", O_WRONLY);
      if (null_fd >= 0) {
        dup2(null_fd, 1);
        dup2(null_fd, 2);
      }
      execl(xvfb.c_str(), "Xvfb", "-displayfd", fd_text.c_str(), "-screen", "0", "1024x768x24", "-nolisten", "tcp",
            static_cast<char*>(nullptr));
      _exit(127);
    }
    close(fds[1]);
    if (pid < 0) {
      close(fds[0]);
      return;
    }
    xvfb_pid_ = pid;
    std::string number;
    char c = 0;
    while (read(fds[0], &c, 1) == 1 && c != '\n') number += c;
    close(fds[0]);
    if (!number.empty()) display_ = ":" + number;
  }

  static void TearDownTestSuite() {
    if (xvfb_pid_ > 0) {
      kill(xvfb_pid_, SIGTERM);
      waitpid(xvfb_pid_, nullptr, 0);
    }
    xvfb_pid_ = -1;
    display_.clear();
  }

  void SetUp() override {
    if (FindProgram("Xvfb").empty()) GTEST_SKIP() << "Xvfb is not installed (apt-get install xvfb); skipping the viewer tests";
    ASSERT_FALSE(display_.empty()) << "could not start Xvfb on a free display";
  }

  // A run folder with frames 0..2 of the moving box in scan/ and a run.json without capture.
  // `frames_json` is the run.json "frames" value.
  std::string MakeRun(const std::string& frames_json = "[0, 3]", std::vector<int> frames = {0, 1, 2}) {
    const std::string run = dir_ / "run";
    fs::create_directories(run + "/scan");
    for (int frame : frames) {
      char name[32];
      std::snprintf(name, sizeof(name), "/scan/%06d.ply", frame);
      WriteMesh(run + name, RedBox(frame));
    }
    WriteTextFile(run + "/run.json", "{\"format\": \"confluent.run/1\", \"frames\": " + frames_json +
                                         ", \"excluded_cameras\": []}\n");
    return run;
  }

  testing::CommandResult View(const std::vector<std::string>& args) {
    std::vector<std::string> all = {"view"};
    all.insert(all.end(), args.begin(), args.end());
    return testing::RunConfluent(all, "export DISPLAY=" + display_ + "; unset WAYLAND_DISPLAY;" + KeepGlDriverLoaded());
  }

  Image Screenshot(const std::string& run, int frame, const std::string& mode) {
    const std::string path = dir_ / ("shot_" + std::to_string(frame) + "_" + mode + ".png");
    const testing::CommandResult result = View({run, "--screenshot", path, "--frame", std::to_string(frame),
                                                "--mode", mode, "--size", "320x240"});
    EXPECT_EQ(result.exit_code, 0) << result.stderr_text;
    if (result.exit_code != 0) return {};
    return ReadImage(path);
  }

  testing::TempDir dir_;
  static inline std::string display_;
  static inline pid_t xvfb_pid_ = -1;
};

TEST_F(ViewCommand, ShadedScreenshotShowsTheBoxWhereItProjects) {
  const std::string run = MakeRun();
  const Image shot = Screenshot(run, 1, "shaded");
  ASSERT_FALSE(shot.empty());
  ASSERT_EQ(shot.width, kWidth);
  ASSERT_EQ(shot.height, kHeight);
  ASSERT_EQ(shot.channels, 3);

  // The red pixels' bounding box is the projection of the frame-1 box's corners.
  const Mesh box = RedBox(1);
  Eigen::AlignedBox2d expected;
  for (int v = 0; v < box.num_vertices(); ++v) expected.extend(ExpectedView().Project(box.vertices.row(v).transpose()));
  Eigen::AlignedBox2d red;
  int red_pixels = 0, other_pixels = 0;
  for (int y = 0; y < shot.height; ++y)
    for (int x = 0; x < shot.width; ++x) {
      if (IsRed(shot, x, y)) {
        red.extend(Eigen::Vector2d(x, y));
        ++red_pixels;
      } else if (!expected.contains(Eigen::Vector2d(x, y))) {
        other_pixels += !IsBackground(shot, x, y);
      }
    }
  ASSERT_GT(red_pixels, 500);
  EXPECT_NEAR(red.min().x(), expected.min().x(), 2.0);
  EXPECT_NEAR(red.max().x(), expected.max().x(), 2.0);
  EXPECT_NEAR(red.min().y(), expected.min().y(), 2.0);
  EXPECT_NEAR(red.max().y(), expected.max().y(), 2.0);
  EXPECT_EQ(other_pixels, 0) << "outside the box everything is background";
  // Shading: the top face (lit at a grazing angle from the front) differs from the front face.
  const Eigen::Vector2i front = PixelOf({0.25, -0.2, 1.0});
  const Eigen::Vector2i top = PixelOf({0.25, 0.0, 1.2 - 1e-3});
  ASSERT_TRUE(IsRed(shot, front.x(), front.y()));
  ASSERT_TRUE(IsRed(shot, top.x(), top.y()));
  EXPECT_GT(std::abs(shot.at<std::uint8_t>(front.x(), front.y(), 0) - shot.at<std::uint8_t>(top.x(), top.y(), 0)), 10);
}

TEST_F(ViewCommand, FramesDifferWhereTheBoxMoved) {
  const std::string run = MakeRun();
  const Image frame0 = Screenshot(run, 0, "shaded");
  const Image frame1 = Screenshot(run, 1, "shaded");
  ASSERT_FALSE(frame0.empty());
  ASSERT_FALSE(frame1.empty());
  // The left part of the frame-0 box is empty in frame 1 and the right part of the frame-1 box
  // was empty in frame 0 (the view stays fixed on frame 0's box).
  const Eigen::Vector2i left = PixelOf({-0.12, -0.2, 1.0});
  const Eigen::Vector2i right = PixelOf({0.37, -0.2, 1.0});
  EXPECT_TRUE(IsRed(frame0, left.x(), left.y()));
  EXPECT_TRUE(IsBackground(frame1, left.x(), left.y()));
  EXPECT_TRUE(IsBackground(frame0, right.x(), right.y()));
  EXPECT_TRUE(IsRed(frame1, right.x(), right.y()));
}

TEST_F(ViewCommand, WireframeDiffersFromShaded) {
  const std::string run = MakeRun();
  const Image shaded = Screenshot(run, 0, "shaded");
  const Image wire = Screenshot(run, 0, "wireframe");
  ASSERT_FALSE(shaded.empty());
  ASSERT_FALSE(wire.empty());
  ASSERT_EQ(wire.width, shaded.width);
  int red_in_wire = 0, wire_pixels = 0, different = 0;
  for (int y = 0; y < wire.height; ++y)
    for (int x = 0; x < wire.width; ++x) {
      red_in_wire += IsRed(wire, x, y);
      wire_pixels += wire.at<std::uint8_t>(x, y, 0) > 150 && wire.at<std::uint8_t>(x, y, 1) > 150;
      different += IsRed(shaded, x, y) && !IsRed(wire, x, y);
    }
  EXPECT_EQ(red_in_wire, 0) << "the wireframe draws edges, not the red faces";
  EXPECT_GT(wire_pixels, 100) << "light grey edges are drawn";
  EXPECT_GT(different, 1000);
  // The centre of the front face lies between edges: background in the wireframe.
  const Eigen::Vector2i face = PixelOf({0.05, -0.2, 1.05});
  EXPECT_TRUE(IsRed(shaded, face.x(), face.y()));
  EXPECT_TRUE(IsBackground(wire, face.x(), face.y()));
}

TEST_F(ViewCommand, InteractiveLoopSurvivesAMissingFrame) {
  // Frames 0..3 in run.json, frame 2 never written.
  const std::string run = MakeRun("[0, 4]", {0, 1, 3});
  const testing::CommandResult result = View({run, "--frame", "2", "--exit-after-frames", "3", "--size", "160x120"});
  EXPECT_EQ(result.exit_code, 0) << result.stderr_text;
  // A scripted screenshot of the missing frame fails and names its file.
  const testing::CommandResult shot = View({run, "--screenshot", dir_ / "missing.png", "--frame", "2"});
  EXPECT_EQ(shot.exit_code, 1);
  EXPECT_NE(shot.stderr_text.find("000002.ply"), std::string::npos) << shot.stderr_text;
  EXPECT_FALSE(fs::exists(dir_ / "missing.png"));
}

// A capture of 3 frames seen by "front" (blue images), "top" (green images) and "left" (excluded
// in run.json); 64x48 pixels.
std::string MakeCapture(const std::string& root) {
  Rig rig;
  rig.cameras.push_back(LookAtCamera("front", {0.0, -3.0, 1.0}, {0.0, 0.0, 1.0}, 64, 48, 60.0));
  rig.cameras.push_back(LookAtCamera("top", {0.0, 0.5, 4.0}, {0.0, 0.0, 1.0}, 64, 48, 60.0));
  rig.cameras.push_back(LookAtCamera("left", {-0.4, 0.0, 1.0}, {0.0, 0.0, 1.0}, 64, 48, 60.0));
  fs::create_directories(root);
  WriteEasyMocap(rig, root);
  const std::uint8_t colors[3][3] = {{0, 0, 255}, {0, 255, 0}, {255, 255, 0}};
  for (int c = 0; c < rig.size(); ++c) {
    fs::create_directories(root + "/images/" + rig.cameras[c].name);
    Image image(64, 48, 3);
    for (std::size_t i = 0; i < image.data.size(); ++i) image.data[i] = colors[c][i % 3];
    for (int frame = 0; frame < 3; ++frame) {
      char name[32];
      std::snprintf(name, sizeof(name), "/%06d.png", frame);
      WriteImage(root + "/images/" + rig.cameras[c].name + name, image);
    }
  }
  return root;
}

bool Near(const Image& image, const Eigen::Vector2i& pixel, int r, int g, int b, int tolerance) {
  const int values[3] = {r, g, b};
  for (int c = 0; c < 3; ++c)
    if (std::abs(image.at<std::uint8_t>(pixel.x(), pixel.y(), c) - values[c]) > tolerance) return false;
  return true;
}

TEST_F(ViewCommand, BlendWeightsAndFrustaFromTheCapture) {
  const std::string run = MakeRun();
  const std::string capture = MakeCapture(dir_ / "capture");
  WriteTextFile(run + "/run.json", "{\"capture\": \"" + capture + "\", \"excluded_cameras\": [\"left\"]}\n");
  const Image weights = Screenshot(run, 0, "weights");
  ASSERT_FALSE(weights.empty());
  // Only "front" (used camera 0, coloured (0.90, 0.30, 0.25)) sees the front face and only "top"
  // (used camera 1, (0.25, 0.70, 0.30)) the top face.
  const Eigen::Vector2i front = PixelOf({0.0, -0.2, 1.0});
  const Eigen::Vector2i top = PixelOf({0.0, 0.0, 1.2 - 1e-3});
  EXPECT_TRUE(Near(weights, front, 230, 77, 64, 4)) << front.transpose();
  EXPECT_TRUE(Near(weights, top, 64, 179, 77, 4)) << top.transpose();

  // Frusta: the excluded camera "left" stands in view, left of the box.
  const std::string plain_path = dir_ / "plain.png", frusta_path = dir_ / "frusta.png";
  ASSERT_EQ(View({run, "--screenshot", plain_path, "--mode", "shaded", "--size", "320x240"}).exit_code, 0);
  ASSERT_EQ(View({run, "--screenshot", frusta_path, "--mode", "shaded", "--frusta", "--size", "320x240"}).exit_code, 0);
  const Image plain = ReadImage(plain_path), frusta = ReadImage(frusta_path);
  const Eigen::Vector2d left_camera = ExpectedView().Project(Eigen::Vector3d(-0.4, 0.0, 1.0));
  int changed = 0, changed_left = 0;
  for (int y = 0; y < plain.height; ++y)
    for (int x = 0; x < plain.width; ++x) {
      int diff = 0;
      for (int c = 0; c < 3; ++c) diff += std::abs(plain.at<std::uint8_t>(x, y, c) - frusta.at<std::uint8_t>(x, y, c));
      if (diff > 30) {
        ++changed;
        changed_left += (Eigen::Vector2d(x, y) - left_camera).norm() < 40.0;
      }
    }
  EXPECT_GT(changed, 30);
  EXPECT_GT(changed_left, 10) << "frustum lines meet at the camera centre " << left_camera.transpose();

  // Textured: the front face shows the front camera's blue, the top face the top camera's green.
  const Image textured = Screenshot(run, 0, "textured");
  ASSERT_FALSE(textured.empty());
  EXPECT_TRUE(Near(textured, front, 0, 0, 255, 12)) << front.transpose();
  EXPECT_TRUE(Near(textured, top, 0, 255, 0, 12)) << top.transpose();
}

TEST_F(ViewCommand, ClearErrors) {
  // Not a run folder.
  fs::create_directories(dir_ / "empty");
  testing::CommandResult result = View({dir_ / "empty"});
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_NE(result.stderr_text.find("not a run folder"), std::string::npos) << result.stderr_text;
  // A run folder without frames.
  fs::create_directories(dir_ / "noframes");
  WriteTextFile(dir_ / "noframes/run.json", "{}\n");
  result = View({dir_ / "noframes"});
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_NE(result.stderr_text.find("no frames"), std::string::npos) << result.stderr_text;
  // No display: says so and suggests xvfb-run.
  const std::string run = MakeRun();
  result = testing::RunConfluent({"view", run}, "unset DISPLAY WAYLAND_DISPLAY;");
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_NE(result.stderr_text.find("DISPLAY"), std::string::npos) << result.stderr_text;
  EXPECT_NE(result.stderr_text.find("xvfb-run"), std::string::npos) << result.stderr_text;
  // Textured needs a capture; this run has none.
  result = View({run, "--screenshot", dir_ / "t.png", "--mode", "textured"});
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_NE(result.stderr_text.find("capture"), std::string::npos) << result.stderr_text;
}

}  // namespace
}  // namespace confluent
