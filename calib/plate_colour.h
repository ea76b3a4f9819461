#pragma once
// Colour response between two cameras of a rig, measured on their clean plates: both see the
// same floor (world z = 0, docs/ARCHITECTURE.md section 3), so where they see the same floor
// point their plate colours differ by the cameras' gains (white balance, exposure). Used to
// render a view with the colour response of a real camera (held-out evaluation).

#include <Eigen/Core>
#include <optional>

#include "calib/camera.h"
#include "calib/capture.h"
#include "core/image.h"

namespace confluent {

struct PlateColourOptions {
  double floor_extent_m = 3.0;   // floor points sampled on a grid over [-extent, extent]^2
  double floor_step_m = 0.02;    // grid spacing
  int min_level = 30;            // both plates' 3x3 means above this (8-bit) for a sample to count
  int min_samples = 200;         // fewer shared samples: no estimate
  // The ratios must agree: an interquartile range above this fraction of the median (in any
  // channel) means the two cameras do not see the same floor at z = 0 (a floor elsewhere, or
  // props): no estimate.
  double max_ratio_spread = 0.1;
};

// Per-channel RGB gain g such that to_plate ~ g * from_plate on the floor seen by both cameras
// (the median ratio of 3x3 means over shared floor points; lens distortion is followed through
// Camera::Project). Plates are RGB8 images of each camera's size. nullopt when the cameras share
// fewer than min_samples floor points or the ratios disagree (max_ratio_spread). Throws InputError("plate") when a plate's size or format
// does not match its camera.
std::optional<Eigen::Vector3d> PlateColourGain(const Camera& from, const Image& from_plate, const Camera& to,
                                               const Image& to_plate, const PlateColourOptions& options = {});

// The gains from each camera in `from` to camera `to` of `capture`, measured on their clean plates
// (CAPTURE/background/<cam>.png|jpg; `to_plate` is camera `to`'s, already read, as RGB8): 1 for a
// camera without a plate or without floor shared with `to`, whose name is then added to
// `unmatched` (when given). Throws InputError naming the file when a plate cannot be read or does
// not fit its camera.
std::vector<Eigen::Vector3d> PlateColourGainsTo(const Capture& capture, const std::vector<int>& from, int to,
                                                const Image& to_plate, std::vector<std::string>* unmatched = nullptr,
                                                const PlateColourOptions& options = {});

}  // namespace confluent
