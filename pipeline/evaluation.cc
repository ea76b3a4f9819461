#include "pipeline/evaluation.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>

#include "calib/plate_colour.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/image_metrics.h"
#include "core/mesh_io.h"
#include "pipeline/evaluation_atlas.h"
#include "pipeline/plot.h"
#include "render/composite.h"

namespace confluent {
namespace fs = std::filesystem;

namespace {

// The scores of one geometry (scan or template) in one held-out camera and frame.
struct ViewScore {
  double iou = NAN;
  double xor_percent = NAN;  // |rendered XOR true| / |true|, %
  double psnr_db = NAN;
  double ssim = NAN;
  double psnr_box_db = NAN;  // second convention: see BoxPsnr
  double psnr_inside_db = NAN;          // inside the intersection of the two silhouettes
  double xor_error_share_percent = NAN; // share of the squared error in the union on XOR pixels
};

// PSNR in the bounding box of `region` with the pixels outside `region` set to black in both
// images (the convention of Neural Body / ZJU-MoCap evaluations): background pixels near the
// actor count as exact, so it is higher than the PSNR inside the region.
double BoxPsnr(const Image& rendered, const Image& real, const Image& region) {
  if (std::none_of(region.data.begin(), region.data.end(), [](std::uint8_t v) { return v != 0; })) return NAN;
  const auto [x0, y0, width, height] = MaskBox(region, 0.0);
  Image a = rendered, b = real, box(region.width, region.height, 1);
  for (int y = 0; y < region.height; ++y)
    for (int x = 0; x < region.width; ++x) {
      box.at<std::uint8_t>(x, y) = (x >= x0 && x < x0 + width && y >= y0 && y < y0 + height) ? 255 : 0;
      if (region.at<std::uint8_t>(x, y)) continue;
      for (int c = 0; c < 3; ++c) a.at<std::uint8_t>(x, y, c) = b.at<std::uint8_t>(x, y, c) = 0;
    }
  return MaskedPsnr(a, b, box);
}

struct Row {
  std::string camera;
  int frame = 0;
  ViewScore scan, templ;
  double vertex_error_m = NAN;  // scan vs ground-truth mesh (once per frame; repeated per camera)
};

// The scores of one rendered view; `region` receives the evaluation region (the union of the
// rendered and the true silhouette).
ViewScore Score(const RenderResult& rendered, const Image& real, const Image& true_mask, Image* region) {
  ViewScore score;
  std::size_t both = 0, either = 0, truth = 0;
  Image intersection(true_mask.width, true_mask.height, 1);
  for (std::size_t i = 0; i < true_mask.data.size(); ++i) {
    const bool a = rendered.silhouette.data[i] != 0, b = true_mask.data[i] != 0;
    both += a && b;
    either += a || b;
    truth += b;
    intersection.data[i] = a && b ? 255 : 0;
  }
  score.iou = either ? static_cast<double>(both) / either : 1.0;
  score.xor_percent = truth ? 100.0 * (either - both) / truth : NAN;
  *region = UnionMask(rendered.silhouette, true_mask);
  if (either > 0) {
    score.psnr_db = MaskedPsnr(rendered.color, real, *region);
    score.ssim = MaskedSsim(rendered.color, real, *region);
    score.psnr_box_db = BoxPsnr(rendered.color, real, *region);
  }
  if (both > 0) {
    score.psnr_inside_db = MaskedPsnr(rendered.color, real, intersection);
    // Squared errors from the PSNRs (peak 1): SSE = MSE * pixels.
    const double sse_union = std::pow(10.0, -score.psnr_db / 10) * either;
    const double sse_inside = std::pow(10.0, -score.psnr_inside_db / 10) * both;
    score.xor_error_share_percent = sse_union > 0 ? 100.0 * std::max(0.0, 1.0 - sse_inside / sse_union) : 0.0;
  }
  return score;
}

double Mean(const std::vector<double>& values) {
  double sum = 0;
  int n = 0;
  for (double v : values)
    if (std::isfinite(v)) sum += v, ++n;
  return n ? sum / n : NAN;
}

double Min(const std::vector<double>& values) {
  double best = NAN;
  for (double v : values)
    if (std::isfinite(v) && !(v >= best)) best = v;
  return best;
}

std::string Csv(double v) {
  if (!std::isfinite(v)) return "";
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", v);
  return text;
}

// The images and (where the run has them) masks of cameras `used` at `frame`.
void ReadInputs(const Capture& capture, const RunFolder& run, const std::vector<int>& used, int frame,
                std::vector<Image>* images, std::vector<Image>* masks) {
  for (int c : used) {
    images->push_back(capture.ReadFrame(c, frame));
    const std::string mask = run.MaskPath(capture.rig().cameras[c].name, frame);
    masks->push_back(fs::exists(mask) ? ReadMaskFile(mask) : Image());
  }
}

// Mean vertex distance between two meshes of the same vertex count.
double MeanVertexError(const Mesh& a, const Mesh& b) { return (a.vertices - b.vertices).rowwise().norm().mean(); }

}  // namespace

void EvaluationOptions::Check() const {
  RequireOption(edge_softness_px >= 0.0 && edge_softness_px <= 5.0, "EvaluationOptions.edge_softness_px",
                edge_softness_px, "in [0, 5] pixels");
  RequireOption(every >= 1, "EvaluationOptions.every", every, ">= 1");
  RequireOption(side_by_side_every >= 0, "EvaluationOptions.side_by_side_every", side_by_side_every, ">= 0");
  RequireOption(atlas_size_px >= 64 && atlas_size_px <= 16384, "EvaluationOptions.atlas_size_px", atlas_size_px,
                "in [64, 16384]");
  texturing.Check();
}

std::string DescribeTextureOptions(const ProjectiveTextureOptions& options) {
  char line[120];
  std::snprintf(line, sizeof line, "best %d camera%s, feather %g px, %s", options.best_k, options.best_k == 1 ? "" : "s",
                options.feather_px, options.colour_balance ? "colour balance" : "no colour balance");
  return line;
}

EvaluationSummary EvaluateRun(const FinishedRun& finished, const Capture& capture, const FrameRange& range,
                              const EvaluationOptions& options, const ProgressCallback& progress) {
  options.Check();
  const RunFolder& run = finished.folder;
  const Rig& rig = capture.rig();
  const ProjectiveTextureOptions& texture_options = options.texturing;

  // Cameras: held out (scored) and the ones the run used (texturing).
  const std::vector<std::string> run_excluded = finished.HeldOutCameras();
  // Scored: the cameras named, else the ones the run held out.
  const std::vector<std::string> heldout_names = options.held_out.empty() ? run_excluded : options.held_out;
  if (heldout_names.empty())
    throw UsageError(finished.manifest ? "--heldout: " + RunManifestPath(run.root) +
                                             " records no held-out camera; name the camera(s) to score"
                                       : "--heldout: name the camera(s) to score (" + run.root +
                                             " has no run.json recording them)");
  std::vector<int> heldout;
  std::vector<std::string> warnings;
  for (const std::string& name : heldout_names) {
    rig.Get(name);  // UsageError listing the known names
    heldout.push_back(rig.IndexOf(name));
    if (std::find(run_excluded.begin(), run_excluded.end(), name) == run_excluded.end())
      warnings.push_back("camera " + name + " was not excluded from the run: its scores are not held-out scores");
  }
  std::vector<int> used;
  std::vector<Camera> used_cameras;
  for (int c = 0; c < rig.size(); ++c) {
    const bool excluded = std::find(run_excluded.begin(), run_excluded.end(), rig.cameras[c].name) != run_excluded.end();
    if (!excluded && std::find(heldout.begin(), heldout.end(), c) == heldout.end()) {
      used.push_back(c);
      used_cameras.push_back(rig.cameras[c]);
    }
  }
  if (used.empty()) throw UsageError("no camera is left for texturing");
  const std::string& masks_dir = options.masks_dir;
  auto true_mask_path = [&](int camera, int frame) {
    const std::string& name = rig.cameras[camera].name;
    if (!masks_dir.empty()) return (fs::path(masks_dir) / name / (FrameStem(frame) + ".png")).string();
    return run.MaskPath(name, frame);
  };
  const std::string& gt_meshes = options.gt_meshes_dir;

  // What the rendered views are seen over: each held-out camera's clean plate (as the camera saw
  // the studio), or black.
  std::vector<Image> plates(heldout.size());
  bool over_plates = options.over_plates;
  for (std::size_t h = 0; h < heldout.size() && over_plates; ++h) {
    const std::string path = capture.BackgroundPath(heldout[h]);
    if (path.empty()) {
      warnings.push_back("no clean plate for held-out camera " + rig.cameras[heldout[h]].name +
                         " (background/): views are scored over black");
      over_plates = false;
    } else {
      plates[h] = ToRgb8(ReadImage(path));
    }
  }
  // The colour response of each held-out camera, matched from the clean plates: per used camera,
  // the RGB gain from its plate to the held-out camera's plate on the floor both see.
  const bool match_colour = over_plates && options.match_colour;
  std::vector<std::vector<Eigen::Vector3d>> view_gains(heldout.size());
  for (std::size_t h = 0; h < heldout.size() && match_colour; ++h) {
    std::vector<std::string> unmatched;
    view_gains[h] = PlateColourGainsTo(capture, used, heldout[h], plates[h], &unmatched);
    for (const std::string& name : unmatched)
      warnings.push_back("no colour match from " + name + " to " + rig.cameras[heldout[h]].name +
                         " (no clean plate, or no floor both see)");
  }
  const double edge_softness = options.edge_softness_px;
  auto seen_over_background = [&](RenderResult rendered, std::size_t h) {
    if (over_plates)
      rendered.color = CompositeOverBackground(rendered, plates[h], capture.BackgroundPath(heldout[h]), edge_softness);
    return rendered;
  };

  // Geometry present in the run.
  const bool has_scan = fs::exists(run.ScanPath(range.first));
  std::vector<int> frames, missing;
  for (int frame = range.first; frame < range.end; frame += options.every) {
    if (fs::exists(run.TemplatePath(frame))) frames.push_back(frame);
    else missing.push_back(frame);
  }
  if (frames.empty()) throw InputError(run.root, "no tracked frame in range: run `confluent run` first");
  if (!missing.empty()) warnings.push_back(std::to_string(missing.size()) + " frame(s) without geometry skipped, first " +
                                           std::to_string(missing.front()));

  std::optional<ProjectiveTexturer> scan_texturer, template_texturer;
  const bool atlas = options.texture == EvaluationOptions::Texture::kAtlas && has_scan;
  std::unique_ptr<AtlasTexturedScan> atlas_scan;  // kAtlas: baked before the scoring loop
  std::vector<int> atlas_index(frames.size(), -1);
  std::string atlas_description;
  if (atlas) {
    AtlasTexturingOptions atlas_options;
    atlas_options.atlas_size_px = options.atlas_size_px;
    atlas_options.supersampling = options.atlas_supersampling;
    atlas_options.texturing = texture_options;
    if (finished.fps() > 0) atlas_options.video.fps = finished.fps();
    std::vector<std::string> view_names;
    for (int c : heldout) view_names.push_back(rig.cameras[c].name);
    atlas_scan = std::make_unique<AtlasTexturedScan>(ReadMesh(run.ScanPath(range.first)), view_names,
                                                     run.Path("evaluation"), atlas_options);
    atlas_description = DescribeAtlasTexturing(atlas_options, atlas_scan->stats());
    for (std::size_t i = 0; i < frames.size(); ++i) {
      if (!fs::exists(run.ScanPath(frames[i]))) continue;
      std::vector<Image> images, masks;
      ReadInputs(capture, run, used, frames[i], &images, &masks);
      atlas_index[i] = atlas_scan->Bake(ReadMesh(run.ScanPath(frames[i])).vertices, used_cameras, images, masks,
                                        match_colour ? view_gains : std::vector<std::vector<Eigen::Vector3d>>());
      ReportProgress(progress, "bake atlas", static_cast<int>(i) + 1, frames.size(), "frame " + std::to_string(frames[i]));
    }
    atlas_scan->FinishBaking();
  } else if (has_scan) {
    const Mesh first = ReadMesh(run.ScanPath(range.first));
    scan_texturer.emplace(first, texture_options);
  }
  template_texturer.emplace(ReadMesh(run.TemplatePath(frames.front())), texture_options);

  fs::create_directories(run.Path("plots"));
  std::vector<Row> rows;
  std::vector<Image> error_sum(heldout.size());
  std::vector<int> error_count(heldout.size(), 0);
  int done = 0;
  for (std::size_t frame_index = 0; frame_index < frames.size(); ++frame_index) {
    const int frame = frames[frame_index];
    std::vector<Image> images, masks;
    ReadInputs(capture, run, used, frame, &images, &masks);
    const Mesh templ = ReadMesh(run.TemplatePath(frame));
    template_texturer->SetFrame(templ.vertices, used_cameras, images, masks);
    std::optional<Mesh> scan;
    double vertex_error = NAN;
    if (has_scan && fs::exists(run.ScanPath(frame))) {
      scan = ReadMesh(run.ScanPath(frame));
      if (!atlas) scan_texturer->SetFrame(scan->vertices, used_cameras, images, masks);
      const fs::path gt = fs::path(gt_meshes) / (FrameStem(frame) + ".ply");
      if (!gt_meshes.empty()) {
        if (!fs::exists(gt)) throw InputError(gt.string(), "ground-truth mesh not found");
        const Mesh truth = ReadMesh(gt.string());
        if (truth.vertices.rows() != scan->vertices.rows())
          throw InputError(gt.string(), "ground-truth mesh has " + std::to_string(truth.vertices.rows()) +
                                            " vertices, the scan " + std::to_string(scan->vertices.rows()));
        vertex_error = MeanVertexError(*scan, truth);
      }
    }
    for (std::size_t h = 0; h < heldout.size(); ++h) {
      const int c = heldout[h];
      const Camera& camera = rig.cameras[c];
      const Image real = capture.ReadFrame(c, frame);
      const std::string mask_path = true_mask_path(c, frame);
      if (!fs::exists(mask_path))
        throw InputError(mask_path, "no silhouette for held-out camera " + camera.name + " (pass --masks DIR, or run the silhouettes stage)");
      const Image truth = ReadMaskFile(mask_path);
      Row row;
      row.camera = camera.name;
      row.frame = frame;
      row.vertex_error_m = vertex_error;
      if (match_colour) template_texturer->SetViewGains(view_gains[h]);
      const RenderResult rendered_template = seen_over_background(template_texturer->Render(camera, true), h);
      Image region;  // of the best geometry: the scan when there is one
      row.templ = Score(rendered_template, real, truth, &region);
      std::optional<RenderResult> rendered_scan;
      if (scan) {
        if (atlas) {
          rendered_scan = seen_over_background(
              atlas_scan->Render(static_cast<int>(h), atlas_index[frame_index], scan->vertices, camera), h);
        } else {
          if (match_colour) scan_texturer->SetViewGains(view_gains[h]);
          rendered_scan = seen_over_background(scan_texturer->Render(camera, true), h);
        }
        row.scan = Score(*rendered_scan, real, truth, &region);
      }
      const RenderResult& best = rendered_scan ? *rendered_scan : rendered_template;
      // The difference inside the evaluation region (the union of the masks, as for PSNR).
      Image difference = AbsoluteDifference(best.color, real);
      for (std::size_t i = 0; i < region.data.size(); ++i)
        if (region.data[i] == 0) difference.ptr<float>()[i] = 0.0f;
      if (error_sum[h].empty()) error_sum[h] = Image(difference.width, difference.height, 1, PixelType::kFloat32);
      for (std::size_t i = 0; i < difference.data.size() / 4; ++i)
        error_sum[h].ptr<float>()[i] += difference.ptr<float>()[i];
      ++error_count[h];
      if (options.side_by_side_every > 0 &&
          (frame - frames.front()) % (options.side_by_side_every * options.every) == 0) {
        Image difference_rgb(difference.width, difference.height, 3);
        for (std::size_t i = 0; i < difference.data.size() / 4; ++i) {
          const auto v = static_cast<std::uint8_t>(std::min(255.0f, 4.0f * 255.0f * difference.ptr<float>()[i]));
          difference_rgb.data[3 * i] = difference_rgb.data[3 * i + 1] = difference_rgb.data[3 * i + 2] = v;
        }
        std::vector<Image> panels = {real};
        std::vector<std::string> captions = {camera.name + " real"};
        if (rendered_scan) panels.push_back(rendered_scan->color), captions.push_back("scan");
        panels.push_back(rendered_template.color), captions.push_back("template");
        panels.push_back(difference_rgb), captions.push_back(std::string("|") + (rendered_scan ? "scan" : "template") + " - real| x4");
        const std::array<int, 4> box = MaskBox(region, 0.15);
        for (Image& panel : panels) panel = CropImage(panel, box);
        const std::string path = run.Path("evaluation/" + camera.name + "/" + FrameStem(frame) + ".png");
        fs::create_directories(fs::path(path).parent_path());
        WriteImage(path, SideBySide(panels, captions));
      }
      rows.push_back(row);
    }
    ReportProgress(progress, "evaluate", ++done, frames.size(), "frame " + std::to_string(frame));
  }

  // Tables, plots and the report.
  auto column = [&](auto get) {
    std::vector<double> values;
    for (const Row& row : rows) values.push_back(get(row));
    return values;
  };
  const std::vector<double> scan_iou = column([](const Row& r) { return r.scan.iou; });
  const std::vector<double> template_iou = column([](const Row& r) { return r.templ.iou; });
  const std::vector<double> scan_psnr = column([](const Row& r) { return r.scan.psnr_db; });
  const std::vector<double> template_psnr = column([](const Row& r) { return r.templ.psnr_db; });
  const std::vector<double> scan_ssim = column([](const Row& r) { return r.scan.ssim; });
  const std::vector<double> template_ssim = column([](const Row& r) { return r.templ.ssim; });
  const std::vector<double> scan_xor = column([](const Row& r) { return r.scan.xor_percent; });
  const std::vector<double> scan_box = column([](const Row& r) { return r.scan.psnr_box_db; });
  const std::vector<double> template_box = column([](const Row& r) { return r.templ.psnr_box_db; });
  const std::vector<double> template_xor = column([](const Row& r) { return r.templ.xor_percent; });
  const std::vector<double> scan_inside = column([](const Row& r) { return r.scan.psnr_inside_db; });
  const std::vector<double> template_inside = column([](const Row& r) { return r.templ.psnr_inside_db; });
  const std::vector<double> scan_share = column([](const Row& r) { return r.scan.xor_error_share_percent; });
  const std::vector<double> template_share = column([](const Row& r) { return r.templ.xor_error_share_percent; });
  std::vector<double> vertex_errors;
  for (std::size_t i = 0; i < rows.size(); i += heldout.size()) vertex_errors.push_back(rows[i].vertex_error_m);

  EvaluationSummary summary;
  summary.heldout = heldout_names;
  summary.frames = static_cast<int>(frames.size());
  summary.has_scan = has_scan;
  summary.background = over_plates ? "clean plate" : "black";
  summary.colour_matched = match_colour;
  summary.edge_softness_px = over_plates ? edge_softness : 0.0;
  summary.texturing = DescribeTextureOptions(texture_options);
  if (atlas) summary.texturing = "scan: " + atlas_description + ", baked with " + summary.texturing;
  summary.scan = {Mean(scan_iou), Min(scan_iou),   Mean(scan_xor),    Mean(scan_psnr),
                  Mean(scan_ssim), Mean(scan_box), Mean(scan_inside), Mean(scan_share)};
  summary.templ = {Mean(template_iou),  Min(template_iou),  Mean(template_xor),    Mean(template_psnr),
                   Mean(template_ssim), Mean(template_box), Mean(template_inside), Mean(template_share)};
  summary.vertex_error_mean_m = Mean(vertex_errors);
  summary.warnings = warnings;

  nlohmann::json json = summary.ToJson();
  std::string csv = "camera,frame,scan_iou,scan_xor_percent,scan_psnr_db,scan_ssim,template_iou,template_xor_percent,"
                    "template_psnr_db,template_ssim,scan_psnr_box_db,template_psnr_box_db,scan_vertex_error_m,"
                    "scan_psnr_inside_db,scan_xor_error_share_percent,template_psnr_inside_db,template_xor_error_share_percent\n";
  for (const Row& r : rows) {
    json["rows"].push_back({{"camera", r.camera}, {"frame", r.frame},
                            {"scan", {{"iou", JsonNumber(r.scan.iou)}, {"xor_percent", JsonNumber(r.scan.xor_percent)},
                                      {"psnr_db", JsonNumber(r.scan.psnr_db)}, {"ssim", JsonNumber(r.scan.ssim)},
                                      {"psnr_box_db", JsonNumber(r.scan.psnr_box_db)},
                                      {"psnr_inside_db", JsonNumber(r.scan.psnr_inside_db)},
                                      {"xor_error_share_percent", JsonNumber(r.scan.xor_error_share_percent)}}},
                            {"template", {{"iou", JsonNumber(r.templ.iou)}, {"xor_percent", JsonNumber(r.templ.xor_percent)},
                                          {"psnr_db", JsonNumber(r.templ.psnr_db)}, {"ssim", JsonNumber(r.templ.ssim)},
                                          {"psnr_box_db", JsonNumber(r.templ.psnr_box_db)},
                                          {"psnr_inside_db", JsonNumber(r.templ.psnr_inside_db)},
                                          {"xor_error_share_percent", JsonNumber(r.templ.xor_error_share_percent)}}},
                            {"scan_vertex_error_m", JsonNumber(r.vertex_error_m)}});
    csv += r.camera + "," + std::to_string(r.frame) + "," + Csv(r.scan.iou) + "," + Csv(r.scan.xor_percent) + "," +
           Csv(r.scan.psnr_db) + "," + Csv(r.scan.ssim) + "," + Csv(r.templ.iou) + "," + Csv(r.templ.xor_percent) + "," +
           Csv(r.templ.psnr_db) + "," + Csv(r.templ.ssim) + "," + Csv(r.scan.psnr_box_db) + "," +
           Csv(r.templ.psnr_box_db) + "," + Csv(r.vertex_error_m) + "," + Csv(r.scan.psnr_inside_db) + "," +
           Csv(r.scan.xor_error_share_percent) + "," + Csv(r.templ.psnr_inside_db) + "," +
           Csv(r.templ.xor_error_share_percent) + "\n";
  }
  WriteTextFile(run.Path("metrics.json"), json.dump(1) + "\n");
  WriteTextFile(run.Path("metrics.csv"), csv);

  // Per-frame plots: the mean over held-out cameras.
  auto per_frame = [&](const std::vector<double>& values) {
    PlotSeries series;
    for (std::size_t i = 0; i < frames.size(); ++i) {
      std::vector<double> at_frame(values.begin() + i * heldout.size(), values.begin() + (i + 1) * heldout.size());
      series.x.push_back(frames[i]);
      series.y.push_back(Mean(at_frame));
    }
    return series;
  };
  auto coloured = [](PlotSeries s, const std::string& label, unsigned char r, unsigned char g, unsigned char b) {
    s.label = label, s.r = r, s.g = g, s.b = b;
    return s;
  };
  std::vector<PlotSeries> iou_series = {coloured(per_frame(template_iou), "template", 200, 90, 30)};
  std::vector<PlotSeries> psnr_series = {coloured(per_frame(template_psnr), "template", 200, 90, 30)};
  if (has_scan) {
    iou_series.push_back(coloured(per_frame(scan_iou), "scan", 30, 90, 200));
    psnr_series.push_back(coloured(per_frame(scan_psnr), "scan", 30, 90, 200));
  }
  WriteImage(run.Path("plots/iou_per_frame.png"), DrawLineChart(iou_series, "Held-out silhouette IoU", "frame", "IoU"));
  WriteImage(run.Path("plots/psnr_per_frame.png"),
             DrawLineChart(psnr_series, "Held-out PSNR inside the union of the masks", "frame", "dB"));
  for (std::size_t h = 0; h < heldout.size(); ++h) {
    Image mean = error_sum[h];
    for (std::size_t i = 0; i < mean.data.size() / 4; ++i) mean.ptr<float>()[i] /= std::max(1, error_count[h]);
    WriteImage(run.Path("plots/error_heatmap_" + rig.cameras[heldout[h]].name + ".png"),
               DrawHeatMap(mean, 0.25, "mean |rendered - real| inside the union of masks, " + rig.cameras[heldout[h]].name));
  }
  WriteTextFile(run.Path("report.html"), ReportHtml(run, summary, rig, heldout));

  return summary;
}

}  // namespace confluent
