// One register -> place path for run, correspond and animate: a registration seeded by a poor
// tracked shape falls back to registering from the scan alone.

#include "pipeline/scan_correspondence.h"

#include <gtest/gtest.h>

#include "core/error.h"
#include "studio/actor.h"

namespace confluent {
namespace {

TEST(ScanCorrespondence, PoorTrackedShapeFallsBackToRegisteringFromTheScanAlone) {
  StudioActorOptions actor_options;
  actor_options.target_triangles = 12000;
  const StudioActor actor = BuildStudioActor(actor_options);
  const BodyTemplate body;
  // A tracked shape far from the actor's (1.75 m): a 1.1 m body.
  ScanCorrespondenceOptions options;
  options.known_shape = BodyShape::Uniform(1.1);
  ScanRegistrationOptions seeded;
  seeded.fit_shape = false;
  seeded.initial_shape = *options.known_shape;
  EXPECT_THROW(RegisterTemplateToScan(body, actor.mesh, seeded, "actor.ply"), InputError);  // the seeded path alone fails

  const ScanCorrespondence result = CorrespondTemplateToScan(body, actor.mesh, "actor.ply", options);
  bool warned = false;
  for (const std::string& warning : result.registration.warnings)
    warned = warned || warning.find("registered from the scan alone") != std::string::npos;
  EXPECT_TRUE(warned);
  EXPECT_GT(result.correspondences.pairs.size(), 50u);
  // The reference keeps the tracked shape: its height is the 1.1 m body's, not the scan's.
  const double reference_height =
      result.reference.vertices.col(2).maxCoeff() - result.reference.vertices.col(2).minCoeff();
  EXPECT_LT(reference_height, 1.3);
}

TEST(ScanCorrespondence, WhatIsNoBodyIsStillRefused) {
  Mesh box;
  box.vertices.resize(8, 3);
  for (int i = 0; i < 8; ++i) box.vertices.row(i) << (i & 1) * 0.5, (i >> 1 & 1) * 0.5, (i >> 2 & 1) * 1.7;
  box.faces.resize(12, 3);
  box.faces << 0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5;
  ScanCorrespondenceOptions options;
  options.known_shape = BodyShape::Uniform(1.75);
  EXPECT_THROW(CorrespondTemplateToScan(BodyTemplate(), box, "box.ply", options), InputError);
}

}  // namespace
}  // namespace confluent
