#pragma once
// Typed exceptions for bad external input (docs/ARCHITECTURE.md section 6). Only app/ catches them.

#include <stdexcept>
#include <string>

namespace confluent {

// Base of every confluent exception. what() is a one-line, human-readable message.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

// A file, folder or flag given by the user is missing, unreadable or malformed.
// what() is "<path>: <problem>" so the user sees which file is at fault.
class InputError : public Error {
 public:
  InputError(const std::string& path, const std::string& problem)
      : Error(path.empty() ? problem : path + ": " + problem), path_(path), problem_(problem) {}
  const std::string& path() const { return path_; }
  const std::string& problem() const { return problem_; }

 private:
  std::string path_;
  std::string problem_;
};

// Writing an output failed (disk full, permissions). Finished outputs are left in place.
class OutputError : public InputError {
 public:
  using InputError::InputError;
};

// A command-line flag or option value is invalid ("--foo: must be positive").
class UsageError : public Error {
 public:
  using Error::Error;
};

// For Options::Check(): throws UsageError "<field> = <value>: must be <rule>" unless `ok`,
// e.g. RequireOption(iterations >= 0, "SilhouetteRefinementOptions.iterations", iterations, ">= 0").
void RequireOption(bool ok, const std::string& field, double value, const std::string& rule);

}  // namespace confluent
