#include "core/bvh_io.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <sstream>

#include "core/atomic_file.h"
#include "core/error.h"

namespace confluent {

namespace {

// Whitespace-separated tokens with their line numbers.
class Tokens {
 public:
  Tokens(const std::string& path, std::istream& in) : path_(path) {
    std::string line;
    int number = 0;
    while (std::getline(in, line)) {
      ++number;
      std::istringstream words(line);
      std::string word;
      while (words >> word) tokens_.push_back({word, number});
    }
    last_line_ = number;
  }
  bool done() const { return next_ >= tokens_.size(); }
  int line() const { return done() ? last_line_ : tokens_[next_].line; }
  const std::string& Peek() const {
    if (done()) Fail("unexpected end of file (truncated?)");
    return tokens_[next_].text;
  }
  std::string Next() {
    const std::string& text = Peek();
    ++next_;
    return text;
  }
  void Expect(const std::string& word) {
    const int at = line();
    const std::string got = Next();
    if (got != word) Fail(at, "expected '" + word + "', got '" + got + "'");
  }
  double Number() {
    const int at = line();
    const std::string text = Next();
    char* end = nullptr;
    const double value = std::strtod(text.c_str(), &end);
    if (end == text.c_str() || *end != '\0' || !std::isfinite(value)) Fail(at, "expected a number, got '" + text + "'");
    return value;
  }
  [[noreturn]] void Fail(const std::string& problem) const { Fail(line(), problem); }
  [[noreturn]] void Fail(int at, const std::string& problem) const {
    throw InputError(path_, "line " + std::to_string(at) + ": " + problem);
  }

 private:
  struct Token {
    std::string text;
    int line;
  };
  std::string path_;
  std::vector<Token> tokens_;
  std::size_t next_ = 0;
  int last_line_ = 0;
};

enum class Channel { kXpos, kYpos, kZpos, kXrot, kYrot, kZrot };

bool ParseChannel(std::string name, Channel* channel) {
  for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  static const std::pair<const char*, Channel> kNames[] = {
      {"xposition", Channel::kXpos}, {"yposition", Channel::kYpos}, {"zposition", Channel::kZpos},
      {"xrotation", Channel::kXrot}, {"yrotation", Channel::kYrot}, {"zrotation", Channel::kZrot}};
  for (const auto& [text, value] : kNames)
    if (name == text) {
      *channel = value;
      return true;
    }
  return false;
}

struct ParsedJoint {
  std::vector<Channel> channels;
  bool end_site = false;
};

// World (Z up) -> BVH (Y up): (x, y, z) -> (x, z, -y).
Eigen::Matrix3d BvhFromWorld() {
  Eigen::Matrix3d M;
  M << 1, 0, 0, 0, 0, 1, 0, -1, 0;
  return M;
}

std::string Num(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.6f", std::abs(v) < 5e-7 ? 0.0 : v);
  return buffer;
}

// Some exporters (Bandai Namco's dataset, for one) put a motionless root above the hips and
// carry the body's travel in the hips' own translation channels, which a Pose cannot hold for a
// non-root joint. When the root does not move in any frame, has that one child, and the child's
// translation channels are the only ones that leave their offsets, the child becomes the root:
// its rotation is composed with the root's and its travel becomes the root translation, so
// every joint's world transform is unchanged. Returns false (motion untouched) otherwise.
bool CollapseStaticRoot(BvhMotion* motion, int child, const std::vector<Eigen::Vector3d>& child_translation) {
  Skeleton& skeleton = motion->skeleton;
  if (child != 1 || skeleton.joints[child].parent != 0 || motion->frames.empty() ||
      child_translation.size() != motion->frames.size())
    return false;
  for (int j = 1; j < skeleton.size(); ++j)
    if (j != child && skeleton.joints[j].parent == 0) return false;
  const Pose& first = motion->frames[0];
  for (const Pose& frame : motion->frames)
    if (frame.local_rotations[0].angularDistance(first.local_rotations[0]) > 1e-9 ||
        (frame.root_translation - first.root_translation).norm() > 1e-9)
      return false;
  const Eigen::Matrix3d root_rotation = first.local_rotations[0].toRotationMatrix();
  const Eigen::Vector3d root_position = skeleton.joints[0].offset_in_parent + first.root_translation;
  const Eigen::Vector3d rest_position = root_position + root_rotation * skeleton.joints[child].offset_in_parent;
  for (std::size_t f = 0; f < motion->frames.size(); ++f) {
    Pose& frame = motion->frames[f];
    const Eigen::Vector3d position = root_position + root_rotation * child_translation[f];
    frame.local_rotations[child] = Eigen::Quaterniond(root_rotation * frame.local_rotations[child]).normalized();
    frame.local_rotations.erase(frame.local_rotations.begin());
    frame.root_translation = position - rest_position;
  }
  Skeleton collapsed;
  for (int j = 1; j < skeleton.size(); ++j) {
    Joint joint = skeleton.joints[j];
    joint.parent = j == child ? -1 : joint.parent - 1;
    if (j == child) joint.offset_in_parent = rest_position;
    collapsed.joints.push_back(joint);
  }
  skeleton = collapsed;
  motion->channels.erase(motion->channels.begin());
  return true;
}

}  // namespace

BvhMotion ReadBvh(const std::string& path, const BvhReadOptions& options) {
  std::ifstream file(path);
  if (!file) throw InputError(path, "cannot open the file");
  Tokens tokens(path, file);
  BvhMotion motion;
  std::vector<ParsedJoint> parsed;
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
  if (options.y_up_to_z_up) axes << 1, 0, 0, 0, 0, -1, 0, 1, 0;

  tokens.Expect("HIERARCHY");
  {
    const int at = tokens.line();
    if (tokens.Next() != "ROOT") tokens.Fail(at, "expected ROOT");
  }
  // Recursive descent with an explicit stack of open joints.
  std::vector<int> stack;
  auto open_joint = [&](const std::string& name, bool end_site) {
    Joint joint;
    joint.name = name;
    joint.parent = stack.empty() ? -1 : stack.back();
    tokens.Expect("{");
    tokens.Expect("OFFSET");
    Eigen::Vector3d offset;
    for (int k = 0; k < 3; ++k) offset(k) = tokens.Number();
    joint.offset_in_parent = options.scale * (axes * offset);
    ParsedJoint info;
    info.end_site = end_site;
    if (!end_site) {
      tokens.Expect("CHANNELS");
      const int at = tokens.line();
      const double count = tokens.Number();
      if (count != 0 && count != 3 && count != 6) tokens.Fail(at, "CHANNELS count must be 0, 3 or 6");
      for (int k = 0; k < static_cast<int>(count); ++k) {
        const int channel_line = tokens.line();
        const std::string text = tokens.Next();
        Channel channel;
        if (!ParseChannel(text, &channel)) tokens.Fail(channel_line, "unknown channel '" + text + "' of joint " + name);
        info.channels.push_back(channel);
      }
    }
    motion.skeleton.joints.push_back(joint);
    parsed.push_back(info);
    stack.push_back(motion.skeleton.size() - 1);
  };
  open_joint(tokens.Next(), false);
  while (!stack.empty()) {
    const int at = tokens.line();
    const std::string word = tokens.Next();
    if (word == "JOINT") {
      if (parsed[stack.back()].end_site) tokens.Fail(at, "JOINT inside an End Site");
      open_joint(tokens.Next(), false);
    } else if (word == "End") {
      tokens.Expect("Site");
      open_joint(motion.skeleton.joints[stack.back()].name + "_end", true);
    } else if (word == "}") {
      stack.pop_back();
    } else {
      tokens.Fail(at, "expected JOINT, End Site or '}', got '" + word + "'");
    }
  }
  tokens.Expect("MOTION");
  tokens.Expect("Frames:");
  int frames_line = tokens.line();
  const double num_frames = tokens.Number();
  if (num_frames < 0 || num_frames != std::floor(num_frames) || num_frames > 1e9) tokens.Fail(frames_line, "bad frame count");
  tokens.Expect("Frame");
  tokens.Expect("Time:");
  motion.frame_time_s = tokens.Number();

  // Drop End Sites unless wanted, keeping parents before children.
  std::vector<int> new_index(parsed.size(), -1);
  Skeleton skeleton;
  for (std::size_t j = 0; j < parsed.size(); ++j) {
    if (parsed[j].end_site && !options.include_end_sites) continue;
    Joint joint = motion.skeleton.joints[j];
    joint.parent = joint.parent < 0 ? -1 : new_index[joint.parent];
    new_index[j] = skeleton.size();
    skeleton.joints.push_back(joint);
    std::vector<std::string> names;
    static const char* kChannelNames[] = {"Xposition", "Yposition", "Zposition", "Xrotation", "Yrotation", "Zrotation"};
    for (Channel c : parsed[j].channels) names.push_back(kChannelNames[static_cast<int>(c)]);
    motion.channels.push_back(names);
  }
  motion.skeleton = skeleton;

  // Translations of the root's child joints per frame, for CollapseStaticRoot.
  std::vector<std::vector<Eigen::Vector3d>> child_translations(skeleton.size());
  std::vector<int> moved_joints;  // non-root joints whose translation channels leave their offset
  for (int f = 0; f < static_cast<int>(num_frames); ++f) {
    if (tokens.done()) tokens.Fail("the file ends after " + std::to_string(f) + " of " +
                                   std::to_string(static_cast<int>(num_frames)) + " frames (truncated)");
    const int frame_line = tokens.line();
    Pose pose = Pose::Rest(skeleton.size());
    for (std::size_t j = 0; j < parsed.size(); ++j) {
      Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
      Eigen::Vector3d translation = Eigen::Vector3d::Zero();
      bool has_translation = false;
      for (Channel channel : parsed[j].channels) {
        if (tokens.done() || tokens.line() != frame_line)
          tokens.Fail(frame_line, "frame " + std::to_string(f) + " has too few values");
        const double value = tokens.Number();
        switch (channel) {
          case Channel::kXpos: translation.x() = value; has_translation = true; break;
          case Channel::kYpos: translation.y() = value; has_translation = true; break;
          case Channel::kZpos: translation.z() = value; has_translation = true; break;
          case Channel::kXrot: rotation = rotation * Eigen::AngleAxisd(value * M_PI / 180, Eigen::Vector3d::UnitX()); break;
          case Channel::kYrot: rotation = rotation * Eigen::AngleAxisd(value * M_PI / 180, Eigen::Vector3d::UnitY()); break;
          case Channel::kZrot: rotation = rotation * Eigen::AngleAxisd(value * M_PI / 180, Eigen::Vector3d::UnitZ()); break;
        }
      }
      if (new_index[j] < 0) continue;
      pose.local_rotations[new_index[j]] = Eigen::Quaterniond(axes * rotation * axes.transpose()).normalized();
      if (has_translation) {
        const Eigen::Vector3d scaled = options.scale * (axes * translation);
        const int joint = new_index[j];
        if (joint == 0) {
          pose.root_translation = scaled;
        } else {
          if (skeleton.joints[joint].parent == 0) {
            child_translations[joint].resize(static_cast<std::size_t>(num_frames), skeleton.joints[joint].offset_in_parent);
            child_translations[joint][f] = scaled;
          }
          if ((scaled - skeleton.joints[joint].offset_in_parent).norm() >
                  1e-3 * std::max(1.0, skeleton.joints[joint].offset_in_parent.norm()) &&
              std::find(moved_joints.begin(), moved_joints.end(), joint) == moved_joints.end())
            moved_joints.push_back(joint);
        }
      }
    }
    if (!tokens.done() && tokens.line() == frame_line)
      tokens.Fail(frame_line, "frame " + std::to_string(f) + " has too many values");
    motion.frames.push_back(pose);
  }
  if (!tokens.done()) tokens.Fail("unexpected data after the last frame");
  if (moved_joints.size() == 1 && CollapseStaticRoot(&motion, moved_joints[0], child_translations[moved_joints[0]]))
    moved_joints.clear();
  if (!moved_joints.empty())
    motion.warnings.push_back("translation channels of non-root joints are ignored (first: joint " +
                              skeleton.joints[moved_joints[0]].name + ")");
  return motion;
}

void WriteBvh(const std::string& path, const Skeleton& skeleton, const std::vector<Pose>& poses, double frame_time_s) {
  const Eigen::Matrix3d M = BvhFromWorld();
  const int n = skeleton.size();
  std::vector<std::vector<int>> children(n);
  for (int j = 1; j < n; ++j) children[skeleton.joints[j].parent].push_back(j);
  std::vector<int> channel_joints;  // joints with channels, in file order
  std::ostringstream out;
  out << "HIERARCHY\n";
  std::function<void(int, int)> write = [&](int j, int depth) {
    const std::string indent(2 * depth, ' ');
    const Eigen::Vector3d offset = 100.0 * M * skeleton.joints[j].offset_in_parent;
    if (j != 0 && children[j].empty()) {
      out << indent << "End Site\n" << indent << "{\n"
          << indent << "  OFFSET " << Num(offset.x()) << " " << Num(offset.y()) << " " << Num(offset.z()) << "\n"
          << indent << "}\n";
      return;
    }
    out << indent << (j == 0 ? "ROOT " : "JOINT ") << skeleton.joints[j].name << "\n" << indent << "{\n";
    out << indent << "  OFFSET " << Num(offset.x()) << " " << Num(offset.y()) << " " << Num(offset.z()) << "\n";
    out << indent << "  CHANNELS " << (j == 0 ? "6 Xposition Yposition Zposition " : "3 ") << "Zrotation Xrotation Yrotation\n";
    channel_joints.push_back(j);
    for (int c : children[j]) write(c, depth + 1);
    out << indent << "}\n";
  };
  write(0, 0);
  out << "MOTION\nFrames: " << poses.size() << "\nFrame Time: " << Num(frame_time_s) << "\n";
  for (const Pose& pose : poses) {
    const Eigen::Vector3d t = 100.0 * M * pose.root_translation;
    out << Num(t.x()) << " " << Num(t.y()) << " " << Num(t.z());
    for (int j : channel_joints) {
      const Eigen::Matrix3d R = j < static_cast<int>(pose.local_rotations.size()) ? pose.local_rotations[j].toRotationMatrix()
                                                                            : Eigen::Matrix3d::Identity();
      const Eigen::Vector3d euler = (M * R * M.transpose()).eulerAngles(2, 0, 1) * (180.0 / M_PI);
      out << " " << Num(euler(0)) << " " << Num(euler(1)) << " " << Num(euler(2));
    }
    out << "\n";
  }
  WriteTextFile(path, out.str());
}

}  // namespace confluent
