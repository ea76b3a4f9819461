#pragma once
// Typed exceptions for bad external input (docs/ARCHITECTURE.md section 6). Only app/ catches them.

#include <initializer_list>
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
// The same for a vector value, printed "(x, y, z)":
// RequireOption(colour.allFinite(), "ShadingOptions.background", {colour.x(), colour.y(), colour.z()}, "finite").
void RequireOption(bool ok, const std::string& field, std::initializer_list<double> value, const std::string& rule);
// For a rule between two fields: throws UsageError "<field_a> = <a> and <field_b> = <b>: must be <rule>"
// unless `ok`, e.g. RequireOptions(near < far, "X.near_m", near, "X.far_m", far, "near_m < far_m").
void RequireOptions(bool ok, const std::string& field_a, double a, const std::string& field_b, double b,
                    const std::string& rule);

}  // namespace confluent
