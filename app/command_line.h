#pragma once
// A small declarative command-line parser for the confluent subcommands.

#include <functional>
#include <map>
#include <string>
#include <vector>

#include "core/progress.h"

namespace confluent::app {

// One --option of a subcommand.
struct OptionSpec {
  std::string name;        // without the leading "--"
  std::string value_name;  // e.g. "DIR"; empty for a boolean switch
  std::string help;
  bool repeated = false;   // may be given several times
  bool required = false;
};

// The parsed command line of one subcommand.
class ParsedArgs {
 public:
  const std::vector<std::string>& positionals() const { return positionals_; }
  bool has(const std::string& name) const { return values_.count(name) > 0; }
  // The value of --name; `fallback` when absent.
  std::string get(const std::string& name, const std::string& fallback = {}) const;
  std::vector<std::string> get_all(const std::string& name) const;
  // Typed getters; throw UsageError "--name: expected a number, got 'x'".
  double get_double(const std::string& name, double fallback) const;
  int get_int(const std::string& name, int fallback) const;

  std::map<std::string, std::vector<std::string>> values_;
  std::vector<std::string> positionals_;
};

// What a subcommand receives besides its arguments.
struct Context {
  // Returns a callback that draws a progress bar on stderr (or plain lines when not a tty).
  std::function<ProgressCallback()> make_progress;
};

// A subcommand: "calib convert" is a two-word name.
struct CommandSpec {
  std::string name;
  std::string summary;                   // one line for `confluent --help`
  std::string usage;                     // e.g. "CAPTURE [--out DIR]"
  std::string description;               // extra paragraphs for `--help`
  int min_positionals = 0;
  int max_positionals = 0;
  std::vector<OptionSpec> options;
  std::function<int(const ParsedArgs&, const Context&)> run;
};

// Parses `args` (after the command name) against `spec`. Throws UsageError on an unknown
// option, a missing value, a missing required option or a wrong number of positionals.
ParsedArgs ParseArgs(const CommandSpec& spec, const std::vector<std::string>& args);

// The text printed by `confluent <command> --help`.
std::string HelpText(const CommandSpec& spec);

}  // namespace confluent::app
