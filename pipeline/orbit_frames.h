#pragma once
// The frames of the 3D video, RUN/renders/<view>/<frame>.png: an orbit around the actor, the
// geometry projectively textured from the used cameras. The render stage draws the frames still
// missing; the deform stage draws each scan as it writes it, while the frame's images are still
// decoded (the same pixels: the vertices as the scan file stores them, the same images and masks).

#include <memory>
#include <string>
#include <vector>

#include "pipeline/run_stages.h"
#include "render/projective_texture.h"

namespace confluent {

class OrbitFrames {
 public:
  // `topology`: the scan (or the posed template) giving the faces and the fallback colours.
  // Throws RenderContextError when no GL context can be created.
  OrbitFrames(const RunInputs& inputs, const RenderStageOptions& options, const Mesh& topology);
  ~OrbitFrames();

  const std::string& view() const { return options_.view; }
  // The used cameras' indices in the rig: whose images and masks Render takes, in this order.
  const std::vector<int>& used() const { return used_; }

  // Renders `frame` from `vertices` as the run folder stores them (ReadMesh of the frame's PLY),
  // the used cameras' images and masks (an empty Image where a camera has none), writes its PNG
  // atomically and logs "render" and "render_write".
  void Render(int frame, const RowMatrixX3d& vertices, const std::vector<Image>& images, const std::vector<Image>& masks,
              TimingLog* timings);

 private:
  const RunInputs& inputs_;
  RenderStageOptions options_;
  std::vector<int> used_;
  std::vector<Camera> used_cameras_, path_;
  std::unique_ptr<ProjectiveTexturer> texturer_;
};

}  // namespace confluent
