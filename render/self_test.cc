#include "render/self_test.h"

#include <cstdint>

namespace confluent {

RenderSelfTest RunRenderSelfTest(MeshRenderer& renderer) {
  Mesh square;
  square.vertices.resize(4, 3);
  square.vertices << -0.25, -0.25, 1.0, 0.25, -0.25, 1.0, 0.25, 0.25, 1.0, -0.25, 0.25, 1.0;
  square.faces.resize(2, 3);
  square.faces << 0, 1, 2, 0, 2, 3;
  renderer.AddMesh(square, "self-test square");
  Camera camera;
  camera.name = "self-test";
  camera.width = 64;
  camera.height = 48;
  camera.K << 40.0, 0.0, 31.5, 0.0, 40.0, 23.5, 0.0, 0.0, 1.0;
  RenderRequest request;
  request.color = false;
  request.silhouette = true;
  const RenderResult result = renderer.Render(camera, request);
  // The square spans pixels 31.5 +- 10 -> columns 22..41 (20 px), rows 14..33 (20 px).
  RenderSelfTest test;
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) test.covered_px += result.silhouette.at<std::uint8_t>(x, y) == 255;
  test.ok = test.covered_px == test.expected_px && result.silhouette.at<std::uint8_t>(22, 14) == 255 &&
            result.silhouette.at<std::uint8_t>(41, 33) == 255 && result.silhouette.at<std::uint8_t>(21, 14) == 0;
  return test;
}

}  // namespace confluent
