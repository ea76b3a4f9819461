#include "pipeline/mask_confidence.h"

#include <algorithm>
#include <map>
#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/error.h"

namespace confluent {

MaskConfidenceRecord MakeMaskConfidenceRecord(const Rig& rig, const MaskTrust& trust, double min_confidence,
                                              const std::string& source) {
  MaskConfidenceRecord record;
  record.source = source;
  record.min_confidence = min_confidence;
  record.mean_confidence = trust.mean_confidence;
  record.camera_frames = trust.camera_frames;
  record.warning = trust.warning;
  record.camera_checked.assign(rig.size(), 0);
  for (const CameraFrameConfidence& entry : trust.checked) ++record.camera_checked.at(entry.camera);
  for (int c = 0; c < rig.size(); ++c) {
    record.camera_names.push_back(rig.cameras[c].name);
    record.camera_confidence.push_back(c < static_cast<int>(trust.camera_confidence.size()) ? trust.camera_confidence[c]
                                                                                              : 1.0);
  }
  for (const CameraFrameConfidence& entry : trust.checked)
    if (entry.confidence < min_confidence) {
      record.low_camera_names.push_back(rig.cameras[entry.camera].name);
      record.low_frames.push_back(entry.frame);
      record.low_confidence.push_back(entry.confidence);
    }
  return record;
}

void WriteMaskConfidence(const std::string& path, const MaskConfidenceRecord& record) {
  nlohmann::json json;
  json["source"] = record.source;
  json["min_confidence"] = record.min_confidence;
  json["mean_confidence"] = record.mean_confidence;
  json["camera_frames"] = record.camera_frames;
  json["num_low_confidence"] = record.low_frames.size();
  json["warning"] = record.warning;
  json["cameras"] = nlohmann::json::array();
  for (std::size_t c = 0; c < record.camera_names.size(); ++c)
    json["cameras"].push_back({{"name", record.camera_names[c]},
                               {"checked", record.camera_checked[c]},
                               {"mean_confidence", record.camera_confidence[c]}});
  json["low"] = nlohmann::json::array();
  for (std::size_t i = 0; i < record.low_frames.size(); ++i)
    json["low"].push_back({{"camera", record.low_camera_names[i]},
                           {"frame", record.low_frames[i]},
                           {"confidence", record.low_confidence[i]}});
  WriteTextFile(path, json.dump(1) + "\n");
}

MaskConfidenceRecord ReadMaskConfidence(const std::string& path) {
  MaskConfidenceRecord record;
  try {
    const nlohmann::json json = nlohmann::json::parse(ReadTextFile(path));
    record.source = json.at("source").get<std::string>();
    record.min_confidence = json.at("min_confidence").get<double>();
    record.mean_confidence = json.at("mean_confidence").get<double>();
    record.camera_frames = json.at("camera_frames").get<int>();
    record.warning = json.at("warning").get<std::string>();
    for (const auto& camera : json.at("cameras")) {
      record.camera_names.push_back(camera.at("name").get<std::string>());
      record.camera_confidence.push_back(camera.at("mean_confidence").get<double>());
      record.camera_checked.push_back(camera.at("checked").get<int>());
    }
    for (const auto& low : json.at("low")) {
      record.low_camera_names.push_back(low.at("camera").get<std::string>());
      record.low_frames.push_back(low.at("frame").get<int>());
      record.low_confidence.push_back(low.at("confidence").get<double>());
    }
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path, std::string("malformed mask confidence record: ") + e.what());
  }
  return record;
}

std::string LowConfidenceList(const MaskConfidenceRecord& record, int max_cameras) {
  std::map<std::string, std::vector<int>> frames;
  for (std::size_t i = 0; i < record.low_frames.size(); ++i)
    frames[record.low_camera_names[i]].push_back(record.low_frames[i]);
  std::vector<std::pair<std::string, std::vector<int>>> cameras(frames.begin(), frames.end());
  std::stable_sort(cameras.begin(), cameras.end(),
                   [](const auto& a, const auto& b) { return a.second.size() > b.second.size(); });
  std::string text;
  const int shown = std::min<int>(max_cameras, static_cast<int>(cameras.size()));
  for (int k = 0; k < shown; ++k) {
    std::vector<int>& list = cameras[k].second;
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
    text += (k ? "; " : "") + cameras[k].first + (list.size() == 1 ? " frame " : " frames ");
    for (std::size_t i = 0; i < list.size();) {
      std::size_t j = i;
      while (j + 1 < list.size() && list[j + 1] == list[j] + 1) ++j;
      text += (i ? ", " : "") + std::to_string(list[i]) + (j > i ? "-" + std::to_string(list[j]) : "");
      i = j + 1;
    }
  }
  if (static_cast<int>(cameras.size()) > shown)
    text += "; and " + std::to_string(cameras.size() - shown) + " more camera(s)";
  return text;
}

}  // namespace confluent
