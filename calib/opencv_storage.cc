#include "calib/opencv_storage.h"

#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <exception>

#include <opencv2/core.hpp>

#include "core/atomic_file.h"
#include "core/error.h"

namespace confluent {
namespace {

// Whether some line of a YAML text starts, after its indentation, with the ':' of a key-value
// pair whose key is empty.
bool HasEntryWithoutName(const std::string& text) {
  std::size_t line_start = 0;
  while (line_start < text.size()) {
    const std::size_t content = text.find_first_not_of(" \t", line_start);
    if (content == std::string::npos) return false;
    if (text[content] == ':') return true;
    const std::size_t end = text.find('\n', content);
    if (end == std::string::npos) return false;
    line_start = end + 1;
  }
  return false;
}

// Whether some line starts with a document marker ("---" or "...") followed by more text on
// the same line, which a YAML document marker may not be.
bool HasMarkerWithText(const std::string& text) {
  std::size_t line_start = 0;
  while (line_start < text.size()) {
    for (const char* marker : {"---", "..."})
      if (text.compare(line_start, 3, marker) == 0 && line_start + 3 < text.size() &&
          std::string(" \t\r\n").find(text[line_start + 3]) == std::string::npos)
        return true;
    const std::size_t end = text.find('\n', line_start);
    if (end == std::string::npos) return false;
    line_start = end + 1;
  }
  return false;
}

// OpenCV 4.6's parsers loop for ever, or crash, on some malformed files; fuzzing keeps finding
// new ones. So a file is first parsed in a child process with `seconds` to finish, and only a
// file the child parsed without hanging or crashing is parsed here.
enum class TrialParse { kFinished, kHung, kCrashed, kNotChecked };

TrialParse ParseInChild(const std::string& path, unsigned seconds) {
  const pid_t child = fork();
  if (child < 0) return TrialParse::kNotChecked;
  if (child == 0) {
    std::signal(SIGALRM, SIG_DFL);  // a fuzzer's or test runner's handler must not catch it
    alarm(seconds);
    try {
      cv::FileStorage storage(path, cv::FileStorage::READ);
    } catch (...) {
    }
    _exit(0);  // no exit handlers: the parent owns them
  }
  int status = 0;
  while (waitpid(child, &status, 0) < 0)
    if (errno != EINTR) return TrialParse::kNotChecked;
  if (WIFSIGNALED(status)) return WTERMSIG(status) == SIGALRM ? TrialParse::kHung : TrialParse::kCrashed;
  return WEXITSTATUS(status) == 0 ? TrialParse::kFinished : TrialParse::kCrashed;
}

}  // namespace

void OpenFileStorage(const std::string& path, const std::string& format_name, cv::FileStorage* storage) {
  const std::string text = ReadTextFile(path);
  // OpenCV 4.6's XML parser dereferences a null pointer when the file ends after "name="
  // (it skips the spaces to the end and reads the quote there), and when a NUL byte follows
  // the '=' (its line reader stops there). No XML document ends with '=' or holds a NUL byte.
  const char* const kSpaces = " \t\r\n\v\f";
  const std::size_t first = text.find_first_not_of(kSpaces);
  const std::size_t last = text.find_last_not_of(kSpaces);
  if (first != std::string::npos && text[first] == '<' && text.find('\0') != std::string::npos)
    throw InputError(path, "cannot parse " + format_name + ": XML with a NUL byte (not a text file)");
  if (first != std::string::npos && text[first] == '<' && text[last] == '=')
    throw InputError(path, "cannot parse " + format_name + ": the file ends inside a tag (truncated?)");
  // OpenCV 4.6's YAML parser loops for ever on a map entry without a name (a line "  : 1"
  // inside a nested map; found by fuzzing). OpenCV never writes such an entry.
  if (first != std::string::npos && text[first] != '<' && text[first] != '{' && HasEntryWithoutName(text))
    throw InputError(path, "cannot parse " + format_name + ": an entry without a name (a line starting with ':')");
  // It also loops for ever on some files whose "---" line goes on with text ("---n:a", then a
  // line without a value and a list; found by fuzzing). OpenCV writes "---" alone on its line.
  if (first != std::string::npos && text[first] != '<' && text[first] != '{' && HasMarkerWithText(text))
    throw InputError(path, "cannot parse " + format_name + ": text after a '---' or '...' document marker on its line");
  constexpr unsigned kParseSeconds = 5;
  const TrialParse trial = ParseInChild(path, kParseSeconds);
  if (trial == TrialParse::kHung)
    throw InputError(path, "cannot parse " + format_name + ": OpenCV's parser did not finish within " +
                               std::to_string(kParseSeconds) + " s (malformed file?)");
  if (trial == TrialParse::kCrashed)
    throw InputError(path, "cannot parse " + format_name + ": OpenCV's parser crashed on it (malformed file?)");
  try {
    storage->open(path, cv::FileStorage::READ);
  } catch (const cv::Exception& exception) {
    throw InputError(path, "cannot parse " + format_name + ": " + exception.err);
  } catch (const std::exception& exception) {  // OpenCV's parser lets std::length_error through
    throw InputError(path, "cannot parse " + format_name + ": " + exception.what());
  }
  if (!storage->isOpened()) throw InputError(path, "cannot open as " + format_name);
  // Callers look entries up by name, which OpenCV asserts on (cv::Exception) unless the top
  // level is a map; an empty file has no top-level node and simply lacks the entries.
  const cv::FileNode top = storage->root();
  if (!top.isMap() && !top.isNone())
    throw InputError(path, "cannot read " + format_name + ": the top level is not a map of named entries");
}

}  // namespace confluent
