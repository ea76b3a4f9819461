#pragma once
// The held-out evaluation summary of a run: its JSON, the terminal table and report.html.

#include <string>
#include <vector>

#include "pipeline/run_folder.h"
#include "calib/camera.h"

#include <nlohmann/json.hpp>

namespace confluent {

// A JSON number, or null for NaN/infinite values (metrics that could not be computed).
nlohmann::json JsonNumber(double value);

// Mean scores of one geometry (the animated scan or the template) over held-out cameras and frames.
struct GeometryScores {
  double iou_mean = 0.0;
  double iou_min = 0.0;
  double xor_percent_mean = 0.0;
  double psnr_db_mean = 0.0;
  double ssim_mean = 0.0;
  double psnr_box_db_mean = 0.0;  // bounding-box convention (see `confluent evaluate --help`)
  // The error split: PSNR inside the intersection of the true and the rendered silhouette (the
  // texture alone), and the share of the squared error in the union that lies in the XOR band
  // (the silhouette mismatch), in %.
  double psnr_inside_db_mean = 0.0;
  double xor_error_share_percent_mean = 0.0;
};

// What `confluent evaluate` found.
struct EvaluationSummary {
  std::vector<std::string> heldout;
  int frames = 0;
  bool has_scan = false;
  std::string background = "black";  // what the rendered views were seen over: "clean plate" or "black"
  bool colour_matched = false;        // input colours matched to each held-out camera's (plates)
  double edge_softness_px = 0.0;      // Gaussian sigma of the outline matting over the plates
  std::string texturing;              // the projective-texturing options, in words
  GeometryScores scan;
  GeometryScores templ;
  double vertex_error_mean_m = 0.0;  // NaN without ground-truth meshes
  std::vector<std::string> warnings;

  nlohmann::json ToJson() const;
  // Reads the summary part of a metrics.json. Throws InputError naming the file.
  static EvaluationSummary Read(const std::string& metrics_json_path);
};

// A short fixed-width table for the terminal.
std::string SummaryTable(const EvaluationSummary& summary);

// report.html of the run: the summary table, the plots, the side-by-side pictures and the
// timings, with paths relative to the run folder.
std::string ReportHtml(const RunFolder& run, const EvaluationSummary& summary, const Rig& rig,
                       const std::vector<int>& heldout);

}  // namespace confluent
