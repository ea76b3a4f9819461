#include "pipeline/evaluation_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "core/atomic_file.h"
#include "core/error.h"
#include "pipeline/mask_confidence.h"

namespace confluent {
namespace fs = std::filesystem;

namespace {

double FromJson(const nlohmann::json& v) { return v.is_number() ? v.get<double>() : NAN; }

nlohmann::json ScoresJson(const GeometryScores& s) {
  return {{"iou_mean", JsonNumber(s.iou_mean)},     {"iou_min", JsonNumber(s.iou_min)},
          {"xor_percent_mean", JsonNumber(s.xor_percent_mean)}, {"psnr_db_mean", JsonNumber(s.psnr_db_mean)},
          {"ssim_mean", JsonNumber(s.ssim_mean)}, {"psnr_box_db_mean", JsonNumber(s.psnr_box_db_mean)},
          {"psnr_inside_db_mean", JsonNumber(s.psnr_inside_db_mean)},
          {"xor_error_share_percent_mean", JsonNumber(s.xor_error_share_percent_mean)}};
}

GeometryScores ScoresFromJson(const nlohmann::json& j) {
  return {FromJson(j.at("iou_mean")), FromJson(j.at("iou_min")), FromJson(j.at("xor_percent_mean")),
          FromJson(j.at("psnr_db_mean")), FromJson(j.at("ssim_mean")), FromJson(j.value("psnr_box_db_mean", nlohmann::json())),
          FromJson(j.value("psnr_inside_db_mean", nlohmann::json())),
          FromJson(j.value("xor_error_share_percent_mean", nlohmann::json()))};
}

std::string Fixed(double v, int decimals) {
  if (!std::isfinite(v)) return "-";
  char text[32];
  std::snprintf(text, sizeof text, "%.*f", decimals, v);
  return text;
}

std::string Escape(const std::string& text) {
  std::string out;
  for (char c : text) out += c == '<' ? "&lt;" : c == '>' ? "&gt;" : c == '&' ? "&amp;" : std::string(1, c);
  return out;
}

}  // namespace

nlohmann::json JsonNumber(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
}

nlohmann::json EvaluationSummary::ToJson() const {
  nlohmann::json json;
  json["format"] = "confluent.metrics/1";
  json["heldout_cameras"] = heldout;
  json["frames"] = frames;
  json["masking"] = "PSNR and SSIM over the union of the true and the rendered silhouette; IoU and XOR over the whole image; "
                    "psnr_box: PSNR in the bounding box of the union, pixels outside the union black in both images";
  json["background"] = background;
  json["colour_matched"] = colour_matched;
  json["edge_softness_px"] = edge_softness_px;
  json["texturing"] = texturing;
  if (has_scan) json["scan"] = ScoresJson(scan);
  json["template"] = ScoresJson(templ);
  json["scan_vertex_error_mean_m"] = JsonNumber(vertex_error_mean_m);
  json["warnings"] = warnings;
  return json;
}

EvaluationSummary EvaluationSummary::Read(const std::string& path) {
  EvaluationSummary summary;
  try {
    const nlohmann::json json = nlohmann::json::parse(ReadTextFile(path));
    summary.heldout = json.at("heldout_cameras").get<std::vector<std::string>>();
    summary.frames = json.at("frames").get<int>();
    summary.has_scan = json.contains("scan");
    summary.background = json.value("background", std::string("black"));
    summary.colour_matched = json.value("colour_matched", false);
    summary.edge_softness_px = json.value("edge_softness_px", 0.0);
    summary.texturing = json.value("texturing", std::string());
    if (summary.has_scan) summary.scan = ScoresFromJson(json.at("scan"));
    summary.templ = ScoresFromJson(json.at("template"));
    summary.vertex_error_mean_m = FromJson(json.at("scan_vertex_error_mean_m"));
    summary.warnings = json.value("warnings", std::vector<std::string>{});
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path, std::string("not a metrics.json: ") + e.what());
  }
  return summary;
}

std::string SummaryTable(const EvaluationSummary& summary) {
  std::ostringstream out;
  std::string cameras;
  for (const std::string& name : summary.heldout) cameras += (cameras.empty() ? "" : ", ") + name;
  out << "held-out evaluation (" << cameras << "; " << summary.frames << " frames; views over "
      << (summary.background == "clean plate" ? "the clean plates" : summary.background)
      << (summary.colour_matched ? ", colours matched" : "")
      << (summary.edge_softness_px > 0 ? ", outline matted" : "") << ")\n";
  char line[160];
  std::snprintf(line, sizeof line, "  %-10s %9s %9s %8s %10s %7s %12s\n", "geometry", "IoU mean", "IoU min", "XOR %", "PSNR dB",
                "SSIM", "PSNR box dB");
  out << line;
  auto row = [&](const char* name, const GeometryScores& s) {
    std::snprintf(line, sizeof line, "  %-10s %9s %9s %8s %10s %7s %12s\n", name, Fixed(s.iou_mean, 4).c_str(),
                  Fixed(s.iou_min, 4).c_str(), Fixed(s.xor_percent_mean, 1).c_str(), Fixed(s.psnr_db_mean, 2).c_str(),
                  Fixed(s.ssim_mean, 4).c_str(), Fixed(s.psnr_box_db_mean, 2).c_str());
    out << line;
  };
  if (summary.has_scan) row("scan", summary.scan);
  row("template", summary.templ);
  const GeometryScores& best = summary.has_scan ? summary.scan : summary.templ;
  if (std::isfinite(best.psnr_inside_db_mean))
    out << "  error split (" << (summary.has_scan ? "scan" : "template") << "): PSNR inside both silhouettes "
        << Fixed(best.psnr_inside_db_mean, 2) << " dB; the silhouette XOR band holds "
        << Fixed(best.xor_error_share_percent_mean, 0) << "% of the squared error in the union\n";
  if (std::isfinite(summary.vertex_error_mean_m))
    out << "  scan vertex error against the ground truth: mean " << Fixed(100.0 * summary.vertex_error_mean_m, 2) << " cm\n";
  return out.str();
}

// The run's silhouette confidence (RUN/mask_confidence.json, when the run wrote one): the mean per
// camera and the camera-frames below the threshold, which tracking followed regardless.
std::string SilhouetteConfidenceHtml(const RunFolder& run) {
  const std::string path = run.Path("mask_confidence.json");
  if (!fs::exists(path)) return "";
  const MaskConfidenceRecord record = ReadMaskConfidence(path);
  std::ostringstream html;
  html << "<h2>Silhouette confidence</h2>\n<p>Each camera's mask against the visual hull of the other cameras (on a "
       << record.source << " of the run's frames, " << record.camera_frames << " camera-frames checked; mean " << Fixed(record.mean_confidence, 3)
       << "). A camera-frame below " << Fixed(record.min_confidence, 2)
       << " disagrees with the others: tracking followed it all the same.</p>\n";
  if (!record.warning.empty()) html << "<p style=\"color:#b00\"><b>Warning:</b> " << Escape(record.warning) << "</p>\n";
  html << "<table><tr><th>camera</th><th>mean confidence</th></tr>\n";
  for (std::size_t c = 0; c < record.camera_names.size(); ++c) {
    html << "<tr><td style=\"text-align:left\">" << Escape(record.camera_names[c]) << "</td>";
    if (record.camera_checked[c] == 0) {
      html << "<td>not checked (held out)</td></tr>\n";
      continue;
    }
    const bool low = record.camera_confidence[c] < record.min_confidence;
    html << "<td" << (low ? " style=\"color:#b00\"" : "") << ">" << Fixed(record.camera_confidence[c], 3) << "</td></tr>\n";
  }
  html << "</table>\n";
  if (!record.low_frames.empty())
    html << "<p><b>" << record.low_frames.size() << " camera-frames below " << Fixed(record.min_confidence, 2)
         << ":</b> " << Escape(LowConfidenceList(record, 1 << 20)) << "</p>\n";
  return html.str();
}

std::string ReportHtml(const RunFolder& run, const EvaluationSummary& summary, const Rig& rig,
                       const std::vector<int>& heldout) {
  std::ostringstream html;
  html << "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>confluent run report</title>\n"
       << "<style>body{font-family:sans-serif;margin:2em;max-width:1400px}table{border-collapse:collapse}"
       << "td,th{border:1px solid #bbb;padding:4px 10px;text-align:right}img{max-width:100%;margin:6px 0}"
       << "pre{background:#f4f4f4;padding:8px}</style></head><body>\n";
  html << "<h1>confluent: held-out evaluation</h1>\n<p>Run: <code>" << Escape(fs::absolute(run.root).string())
       << "</code></p>\n";
  html << "<h2>Summary</h2>\n<pre>" << Escape(SummaryTable(summary)) << "</pre>\n";
  html << "<p>PSNR and SSIM are computed inside the union of the true and the rendered silhouette; IoU and the XOR "
          "error (% of the true silhouette area) over the whole image. The rendered views are seen over "
       << (summary.background == "clean plate" ? "each held-out camera's clean plate" : "black")
       << ", so pixels only the real silhouette covers compare the actor with that background"
       << (summary.colour_matched ? "; the input cameras' colours are matched to the held-out camera's by RGB gains "
                                    "measured on the floor both clean plates show"
                                  : "")
       << ". \"PSNR box\" is the PSNR in the bounding box of "
          "that union with the pixels outside the union black in both images (the Neural Body / ZJU-MoCap "
          "convention). The error split separates texture from silhouette: the PSNR inside the intersection of the "
          "two silhouettes, and the share of the squared error in the union that falls on pixels only one of them "
          "covers.</p>\n";
  for (const std::string& warning : summary.warnings) html << "<p><b>Warning:</b> " << Escape(warning) << "</p>\n";
  html << SilhouetteConfidenceHtml(run);
  if (fs::exists(run.VideoPath("orbit")))
    html << "<h2>3D video</h2>\n<video controls width=\"960\" src=\"renders/orbit.mp4\"></video>\n";
  html << "<h2>Per frame</h2>\n<img src=\"plots/iou_per_frame.png\"><br><img src=\"plots/psnr_per_frame.png\">\n";
  html << "<h2>Error heat maps</h2>\n";
  for (int c : heldout) html << "<img src=\"plots/error_heatmap_" << rig.cameras[c].name << ".png\" width=\"640\">\n";
  html << "<h2>Real | rendered | difference</h2>\n";
  for (int c : heldout) {
    const fs::path dir = fs::path(run.root) / "evaluation" / rig.cameras[c].name;
    if (!fs::is_directory(dir)) continue;
    std::vector<std::string> files;
    for (const auto& entry : fs::directory_iterator(dir)) files.push_back(entry.path().filename().string());
    std::sort(files.begin(), files.end());
    for (const std::string& file : files)
      html << "<p>" << rig.cameras[c].name << " frame " << fs::path(file).stem().string() << "<br><img src=\"evaluation/"
           << rig.cameras[c].name << "/" << file << "\"></p>\n";
  }
  if (fs::exists(run.Path("timings.csv"))) {
    TimingLog timings(run.Path("timings.csv"));
    html << "<h2>Time per stage</h2>\n<table><tr><th>stage</th><th>seconds</th></tr>\n";
    for (const char* stage : {"silhouettes", "tracking", "correspondences", "deform_factor", "deform", "deform_write", "refine_factor",
                              "refine_read", "refine", "photo_refine_read", "photo_refine", "render_read", "render",
                              "render_write", "video"})
      html << "<tr><td style=\"text-align:left\">" << stage << "</td><td>" << Fixed(timings.StageSeconds(stage), 1) << "</td></tr>\n";
    html << "</table>\n";
  }
  html << "</body></html>\n";
  return html.str();
}

}  // namespace confluent
