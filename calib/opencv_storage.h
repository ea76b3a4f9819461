#pragma once
// Opening OpenCV FileStorage files (YAML, XML, JSON) for reading, with the checks that OpenCV
// itself lacks. Used by the EasyMocap reader and the OpenCV XML importer.

#include <string>

#include <opencv2/core/persistence.hpp>

namespace confluent {

// Opens `path` for reading into `storage`. `format_name` ("YAML", "OpenCV XML/YAML") words the
// errors. Throws InputError naming the file when it is missing or unreadable, when OpenCV's
// parser rejects it (cv::Exception, or the std::length_error it lets through), and for the
// malformed XML that crashes OpenCV 4.6's parser instead (a file that ends right after an
// attribute's '=', or XML holding a NUL byte), for the YAML that makes it loop for ever (a map
// entry without a name; all found by fuzzing), or when the top level is not
// a map (OpenCV's lookup by name would throw cv::Exception).
void OpenFileStorage(const std::string& path, const std::string& format_name, cv::FileStorage* storage);

}  // namespace confluent
