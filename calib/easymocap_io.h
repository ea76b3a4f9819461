#pragma once
// Native calibration format: EasyMocap intri.yml / extri.yml (OpenCV FileStorage YAML).

#include <string>

#include "calib/camera.h"

namespace confluent {

// Reads intri.yml (names, K_<cam>, dist_<cam> 1x5 or 5x1 (fewer values are zero-padded),
// H_<cam>, W_<cam>; a missing dist means no distortion; more than 5 coefficients are accepted
// only when the extra ones are zero) and extri.yml (Rot_<cam> 3x3, or R_<cam> Rodrigues 3x1;
// T_<cam> 3x1).
// Throws InputError naming the file and the camera for a missing or non-numeric entry,
// a NaN, or a rotation that is not a rotation. The rig is Check()ed.
Rig ReadEasyMocap(const std::string& intri_path, const std::string& extri_path);

// Writes `dir`/intri.yml and `dir`/extri.yml (atomically). Throws OutputError.
void WriteEasyMocap(const Rig& rig, const std::string& dir);

}  // namespace confluent
