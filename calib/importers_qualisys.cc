// Qualisys .qca.txt (XML). Conventions as in Pose2Sim's read_qca (Pagnon et al. 2022):
//   - focalLengthU/V, centerPointU/V are in 1/64 pixel; the principal point is relative to the
//     sensor, so fov_video left/top is subtracted; the image size is the fov_video rectangle;
//   - distortion coefficients are divided by 64 as well (Pose2Sim's convention);
//   - transform x y z is the camera centre in the world (mm); r11..r33 rows give the rotation
//     of a camera frame with y up and z backwards, so cam_from_world = Rx(pi) * R.

#include <cmath>
#include <map>

#include <Eigen/Geometry>

#include "calib/importers_internal.h"
#include "core/atomic_file.h"
#include "core/error.h"

namespace confluent {
namespace importers_internal {

namespace {

struct XmlElement {
  std::map<std::string, std::string> attributes;
  std::string content;  // text between the opening and closing tags (empty when self-closing)
};

// Every <tag ...> element of `text` (not nested in itself), with attributes and content.
std::vector<XmlElement> FindXmlElements(const std::string& text, const std::string& tag) {
  std::vector<XmlElement> elements;
  std::size_t position = 0;
  const std::string open = "<" + tag;
  while ((position = text.find(open, position)) != std::string::npos) {
    const std::size_t after = position + open.size();
    if (after >= text.size() || !(std::isspace(static_cast<unsigned char>(text[after])) || text[after] == '>' ||
                                  text[after] == '/')) {
      position = after;
      continue;
    }
    XmlElement element;
    std::size_t i = after;
    bool self_closing = false;
    while (i < text.size()) {
      while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
      if (i >= text.size()) break;
      if (text[i] == '>') {
        ++i;
        break;
      }
      if (text.compare(i, 2, "/>") == 0) {
        self_closing = true;
        i += 2;
        break;
      }
      const std::size_t name_begin = i;
      while (i < text.size() && text[i] != '=' && !std::isspace(static_cast<unsigned char>(text[i])) &&
             text[i] != '>' && text[i] != '/')
        ++i;
      const std::string name = text.substr(name_begin, i - name_begin);
      while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
      if (i < text.size() && text[i] == '=') {
        ++i;
        while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
        if (i < text.size() && (text[i] == '"' || text[i] == '\'')) {
          const char quote = text[i++];
          const std::size_t value_end = text.find(quote, i);
          if (value_end == std::string::npos) break;
          element.attributes[name] = text.substr(i, value_end - i);
          i = value_end + 1;
        }
      } else if (name.empty()) {
        ++i;  // skip a stray character
      }
    }
    if (!self_closing) {
      const std::size_t close = text.find("</" + tag + ">", i);
      element.content = text.substr(i, close == std::string::npos ? std::string::npos : close - i);
      position = close == std::string::npos ? text.size() : close;
    } else {
      position = i;
    }
    elements.push_back(element);
  }
  return elements;
}

double XmlNumber(const XmlElement& element, const std::string& name, const std::string& path,
                 const std::string& where) {
  const auto found = element.attributes.find(name);
  if (found == element.attributes.end()) throw InputError(path, where + ": missing attribute " + name);
  return ParseNumber(found->second, path, where + " " + name);
}

}  // namespace

Rig ReadQualisys(const std::string& path) {
  const std::string text = ReadTextFile(path);
  const std::vector<XmlElement> elements = FindXmlElements(text, "camera");
  if (elements.empty()) throw InputError(path, "no <camera> elements (not a Qualisys .qca.txt file?)");
  // Video cameras only (as Pose2Sim), unless there are none.
  std::vector<const XmlElement*> selected;
  for (const auto& element : elements) {
    const auto model = element.attributes.find("model");
    const std::string name = model == element.attributes.end() ? "" : Lower(model->second);
    if (name.find("video") != std::string::npos || name == "none" || name.empty()) selected.push_back(&element);
  }
  if (selected.empty())
    for (const auto& element : elements) selected.push_back(&element);

  Rig rig;
  int index = 0;
  for (const XmlElement* element : selected) {
    ++index;
    const auto serial = element->attributes.find("serial");
    Camera camera;
    camera.name = SanitizeName(serial != element->attributes.end() && !serial->second.empty()
                                   ? serial->second
                                   : "cam" + std::to_string(index));
    const std::string where = "camera " + camera.name;
    const std::vector<XmlElement> fov = FindXmlElements(element->content, "fov_video");
    const std::vector<XmlElement> transform = FindXmlElements(element->content, "transform");
    const std::vector<XmlElement> intrinsic = FindXmlElements(element->content, "intrinsic");
    if (fov.empty() || transform.empty() || intrinsic.empty())
      throw InputError(path, where + ": needs <fov_video>, <transform> and <intrinsic>");
    const double left = XmlNumber(fov[0], "left", path, where);
    const double top = XmlNumber(fov[0], "top", path, where);
    camera.width = static_cast<int>(std::lround(XmlNumber(fov[0], "right", path, where) - left + 1));
    camera.height = static_cast<int>(std::lround(XmlNumber(fov[0], "bottom", path, where) - top + 1));
    const XmlElement& in = intrinsic[0];
    const double fu = XmlNumber(in, "focalLengthU", path, where) / 64.0;
    const double fv = XmlNumber(in, "focalLengthV", path, where) / 64.0;
    const double cu = XmlNumber(in, "centerPointU", path, where) / 64.0 - left;
    const double cv = XmlNumber(in, "centerPointV", path, where) / 64.0 - top;
    double skew = 0.0;
    if (in.attributes.count("skew")) skew = XmlNumber(in, "skew", path, where) / 64.0;
    camera.K = IntrinsicMatrix(fu, fv, cu, cv, skew);
    // Read before assigning: an exception inside Eigen's comma initializer would abort.
    const double k1 = XmlNumber(in, "radialDistortion1", path, where) / 64.0;
    const double k2 = XmlNumber(in, "radialDistortion2", path, where) / 64.0;
    const double p1 = XmlNumber(in, "tangentalDistortion1", path, where) / 64.0;
    const double p2 = XmlNumber(in, "tangentalDistortion2", path, where) / 64.0;
    camera.dist << k1, k2, p1, p2, 0.0;
    if (in.attributes.count("radialDistortion3")) camera.dist[4] = XmlNumber(in, "radialDistortion3", path, where) / 64.0;
    const XmlElement& tr = transform[0];
    Eigen::Matrix3d rotation;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        rotation(r, c) = XmlNumber(tr, "r" + std::to_string(r + 1) + std::to_string(c + 1), path, where);
    const Eigen::Vector3d center(XmlNumber(tr, "x", path, where), XmlNumber(tr, "y", path, where),
                                 XmlNumber(tr, "z", path, where));
    camera.rotation = Orthonormalize(Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal() * rotation);
    camera.translation = -camera.rotation * center;
    rig.cameras.push_back(camera);
  }
  return rig;
}

}  // namespace importers_internal
}  // namespace confluent
