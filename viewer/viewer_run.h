#pragma once
// What `confluent view` plays: the frames of a run folder (scan/ or template/), the capture it
// came from, and a small cache of loaded frames.

#include <list>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/mesh.h"

namespace confluent {

// A run folder as the viewer sees it.
struct ViewerRun {
  std::string root;                         // the run folder
  std::string mesh_dir;                     // root/scan or root/template
  std::string mesh_kind;                    // "scan" or "template"
  int first_frame = 0;                      // timeline range, inclusive
  int last_frame = -1;
  std::vector<int> present;                 // frames with a mesh file, ascending
  std::string capture;                      // capture folder ("" = none known)
  std::vector<std::string> excluded_cameras;  // cameras not used for texturing
  double fps = 0.0;                         // the run's frame rate (0: not recorded)

  int num_frames() const { return last_frame - first_frame + 1; }
  bool has_frame(int frame) const;
  std::string FramePath(int frame) const;   // mesh_dir/<frame:06d>.ply
};

// Opens `root`: requires run.json (capture and excluded_cameras are read from it; "frames":
// [A, B) widens the timeline so that missing frames show) and <frame:06d>.ply files in scan/,
// or in template/ when there is no scan/. `capture_override` (when not empty) replaces the
// capture named in run.json. Throws InputError naming the folder or file: not a folder, not a
// run folder (no run.json), malformed run.json, no frames.
ViewerRun OpenViewerRun(const std::string& root, const std::string& capture_override = {});

// The meshes of the most recently used frames, loaded on demand. A frame that is missing or
// cannot be read is remembered with its error message.
class FrameCache {
 public:
  FrameCache(const ViewerRun* run, int capacity);
  // The frame's mesh, or nullptr with `*error` set (missing file, unreadable mesh).
  std::shared_ptr<const Mesh> Get(int frame, std::string* error);

 private:
  struct Entry {
    std::shared_ptr<const Mesh> mesh;
    std::string error;
  };
  const ViewerRun* run_;
  int capacity_;
  std::map<int, Entry> entries_;
  std::list<int> recent_;  // most recent first
};

}  // namespace confluent
