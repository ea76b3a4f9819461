// The studio actor's procedural albedo: skin, hair, a striped shirt, trousers and shoes placed
// on the rest-pose surface: skin, hair and a face, a plaid shirt with a logo, jeans, shoes, and
// two octaves of value noise for fine detail.

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "studio/actor_internal.h"

namespace confluent::actor_internal {
namespace {

// Lattice value noise in [0, 1] with smooth interpolation.
double Hash(std::int64_t x, std::int64_t y, std::int64_t z, unsigned seed) {
  std::uint64_t h = static_cast<std::uint64_t>(x) * 0x9E3779B97F4A7C15ull ^ static_cast<std::uint64_t>(y) * 0xC2B2AE3D27D4EB4Full ^
                    static_cast<std::uint64_t>(z) * 0x165667B19E3779F9ull ^ (static_cast<std::uint64_t>(seed) << 32);
  h ^= h >> 33;
  h *= 0xff51afd7ed558ccdull;
  h ^= h >> 33;
  h *= 0xc4ceb9fe1a85ec53ull;
  h ^= h >> 33;
  return static_cast<double>(h >> 11) / static_cast<double>(1ull << 53);
}

double ValueNoise(const Vector3d& p, unsigned seed) {
  const Eigen::Vector3d fl = p.array().floor();
  const Eigen::Vector3d t = p - fl;
  const Eigen::Vector3d w = t.array() * t.array() * (3.0 - 2.0 * t.array());
  const auto x = static_cast<std::int64_t>(fl.x()), y = static_cast<std::int64_t>(fl.y()), z = static_cast<std::int64_t>(fl.z());
  double result = 0.0;
  for (int c = 0; c < 8; ++c) {
    const int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
    const double weight = (dx ? w.x() : 1 - w.x()) * (dy ? w.y() : 1 - w.y()) * (dz ? w.z() : 1 - w.z());
    result += weight * Hash(x + dx, y + dy, z + dz, seed);
  }
  return result;
}

Eigen::Vector3d SrgbToLinear(double r, double g, double b) {
  auto f = [](double c) { return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4); };
  return Eigen::Vector3d(f(r), f(g), f(b));
}

// True when x is within half_width of a multiple of period.
bool OnLine(double x, double period, double half_width) {
  const double r = x - period * std::round(x / period);
  return std::abs(r) < half_width;
}

}  // namespace

// Procedural albedo (linear RGB) of a rest-pose point.
Eigen::Vector3d Albedo(const Vector3d& p, BodySegment segment, const std::vector<Vector3d>& J, double s,
                       unsigned seed) {
  const Eigen::Vector3d skin = SrgbToLinear(0.87, 0.67, 0.56);
  const Eigen::Vector3d hair = SrgbToLinear(0.22, 0.13, 0.07);
  const Eigen::Vector3d shirt = SrgbToLinear(0.80, 0.20, 0.16);
  const Eigen::Vector3d shirt_line = SrgbToLinear(0.12, 0.14, 0.36);
  const Eigen::Vector3d shirt_thin = SrgbToLinear(0.95, 0.85, 0.55);
  const Eigen::Vector3d denim = SrgbToLinear(0.20, 0.28, 0.50);
  const Eigen::Vector3d white = SrgbToLinear(0.93, 0.93, 0.90);
  const Vector3d q = p / s;  // unit-height coordinates
  Eigen::Vector3d color = skin;
  auto trousers = [&]() {
    Eigen::Vector3d c = denim;
    if (OnLine(q.x() + q.y() + q.z(), 0.012, 0.002)) c *= 0.8;  // fine diagonal twill
    return c;
  };
  switch (segment) {
    case BodySegment::kHead: {
      const Vector3d c = (J[kJointHead] / s) + Vector3d(0.0, 0.01, 0.085);
      const Vector3d d = q - c;
      const bool face = d.y() > 0.0 && d.z() < 0.03 - 0.3 * std::max(0.0, -d.y());
      color = skin;
      if (!face && d.z() > -0.075 + 0.3 * std::max(0.0, d.y())) color = hair;
      if (d.z() > 0.032 + 0.15 * std::max(0.0, d.y() - 0.05)) color = hair;
      if (d.y() > 0.05) {
        for (double side : {-1.0, 1.0}) {
          const double ex = d.x() - side * 0.032, ez = d.z() - 0.008;
          if (ex * ex / (0.013 * 0.013) + ez * ez / (0.008 * 0.008) < 1.0) color = SrgbToLinear(0.95, 0.95, 0.95);
          if (ex * ex + ez * ez < 0.0055 * 0.0055) color = SrgbToLinear(0.12, 0.22, 0.35);
          if (std::abs(ex) < 0.016 && std::abs(d.z() - 0.027) < 0.0035) color = hair;  // eyebrows
        }
        if (std::abs(d.x()) < 0.024 && std::abs(d.z() + 0.046) < 0.0065) color = SrgbToLinear(0.72, 0.30, 0.30);
      }
      break;
    }
    case BodySegment::kNeck:
      color = skin;
      break;
    case BodySegment::kUpperTorso:
    case BodySegment::kLeftUpperArm:
    case BodySegment::kRightUpperArm: {
      color = shirt;
      // Plaid in surface coordinates: around and along the torso (or the arm).
      double u = 0.0, v = 0.0;
      if (segment == BodySegment::kUpperTorso) {
        u = std::atan2(q.x(), q.y() - J[kJointChest].y() / s) * 0.15;
        v = q.z();
      } else {
        const int shoulder = segment == BodySegment::kLeftUpperArm ? kJointLeftShoulder : kJointRightShoulder;
        const Vector3d axis = (J[shoulder + 1] - J[shoulder]).normalized();
        const Vector3d d = p - J[shoulder];
        const Vector3d ref = (Vector3d::UnitY() - axis.y() * axis).normalized();
        const Vector3d radial = d - d.dot(axis) * axis;
        u = std::atan2(radial.dot(axis.cross(ref)), radial.dot(ref)) * 0.045;
        v = d.dot(axis) / s;
      }
      if (OnLine(u, 0.07, 0.008) || OnLine(v, 0.07, 0.008))
        color = shirt_line;
      else if (OnLine(u + 0.035, 0.07, 0.0025) || OnLine(v + 0.035, 0.07, 0.0025))
        color = shirt_thin;
      if (segment != BodySegment::kUpperTorso) {
        // Short sleeves with a hem; skin below.
        const int shoulder = segment == BodySegment::kLeftUpperArm ? kJointLeftShoulder : kJointRightShoulder;
        double t = 0.0;
        SegmentDistance(p, J[shoulder], J[shoulder + 1], &t);
        if (t > 0.62) color = skin;
        else if (t > 0.56) color = shirt_line;
      } else {
        const double chest_y = J[kJointChest].y() / s;
        if (q.y() > chest_y + 0.04) {
          // Front: a yellow logo on the left chest and a white placket with buttons.
          const double lx = q.x() + 0.085, lz = q.z() - 1.33;
          const double r = std::sqrt(lx * lx + lz * lz);
          if (r < 0.055) color = SrgbToLinear(0.98, 0.82, 0.12);
          if (r < 0.03) color = SrgbToLinear(0.10, 0.45, 0.25);
          if (std::abs(lx) < 0.006 && r < 0.055) color = SrgbToLinear(0.98, 0.98, 0.95);
          if (std::abs(q.x()) < 0.012 && q.z() < 1.40) {
            color = white;
            if (OnLine(q.z() - 1.0, 0.06, 0.006) && std::abs(q.x()) < 0.006) color = SrgbToLinear(0.1, 0.1, 0.1);
          }
        }
        if (q.z() < 1.02) color = shirt_line;  // hem tucked in at the waist
      }
      break;
    }
    case BodySegment::kLeftForearm:
    case BodySegment::kRightForearm: {
      color = skin;
      if (segment == BodySegment::kLeftForearm) {
        double t = 0.0;
        SegmentDistance(p, J[kJointLeftElbow], J[kJointLeftWrist], &t);
        if (t > 0.82 && t < 0.93) color = SrgbToLinear(0.08, 0.08, 0.08);  // wristwatch
      }
      break;
    }
    case BodySegment::kLeftHand:
    case BodySegment::kRightHand:
      color = skin;
      break;
    case BodySegment::kLowerTorso: {
      color = trousers();
      const double belt_z = q.z() - 0.985;
      if (std::abs(belt_z) < 0.018) {
        color = SrgbToLinear(0.30, 0.18, 0.08);
        if (q.y() > 0.05 && std::abs(q.x()) < 0.03) color = SrgbToLinear(0.85, 0.72, 0.30);
      } else if (q.z() > 1.003) {
        color = shirt_line;
      }
      // Back pockets with orange stitching.
      if (q.y() < -0.05 && q.z() > 0.80 && q.z() < 0.94 && std::abs(q.x()) > 0.035 && std::abs(q.x()) < 0.135) {
        const double ax = std::abs(q.x());
        const bool edge = ax < 0.042 || ax > 0.128 || q.z() > 0.933 || q.z() < 0.807;
        color = edge ? SrgbToLinear(0.92, 0.55, 0.15) : denim * 0.85;
      }
      break;
    }
    case BodySegment::kLeftThigh:
    case BodySegment::kRightThigh:
    case BodySegment::kLeftShank:
    case BodySegment::kRightShank: {
      color = trousers();
      const bool left = segment == BodySegment::kLeftThigh || segment == BodySegment::kLeftShank;
      const int hip = left ? kJointLeftHip : kJointRightHip;
      const int a = (segment == BodySegment::kLeftThigh || segment == BodySegment::kRightThigh) ? hip : hip + 1;
      double t = 0.0;
      SegmentDistance(p, J[a], J[a + 1], &t);
      const Vector3d on_axis = J[a] + t * (J[a + 1] - J[a]);
      const Vector3d radial = (p - on_axis).normalized();
      const double outward = left ? -radial.x() : radial.x();
      if (outward > 0.97) color = white;  // side stripe
      if (q.z() < 0.11) color = white;    // socks
      break;
    }
    case BodySegment::kLeftFoot:
    case BodySegment::kRightFoot: {
      color = white;
      const bool left = segment == BodySegment::kLeftFoot;
      const int toe = left ? kJointLeftToe : kJointRightToe;
      if (q.y() > J[toe].y() / s - 0.06) color = SrgbToLinear(0.85, 0.12, 0.10);
      if (OnLine(q.y() - q.z() * 1.5, 0.06, 0.008) && q.z() > 0.03) color = SrgbToLinear(0.85, 0.12, 0.10);
      if (q.z() < 0.018) color = SrgbToLinear(0.10, 0.10, 0.10);
      break;
    }
  }
  // Fine detail: two octaves of value noise modulate the brightness by about +-10%.
  const double noise = 0.6 * ValueNoise(q / 0.018, seed) + 0.4 * ValueNoise(q / 0.006, seed + 7);
  return (color * (0.9 + 0.2 * noise)).cwiseMin(1.0);
}

}  // namespace confluent::actor_internal
