#pragma once
// A picture of the template <-> scan correspondences, for `confluent correspond`: the template
// (left) and the scan (right) seen from the front, the paired triangles coloured by segment.

#include <string>

#include "core/mesh.h"
#include "deform/correspondences.h"
#include "tracking/body_template.h"
#include "tracking/scan_registration.h"

namespace confluent {

// Renders the picture (1200x900 PNG) to `path`. Throws Error when rendering fails (no EGL), or
// OutputError when the file cannot be written.
void WritePairsPicture(const std::string& path, const Mesh& template_mesh, const Mesh& scan, const Correspondences& pairs,
                       const ScanRegistration& registration, const BodyTemplate& body);

}  // namespace confluent
