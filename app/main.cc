// The confluent command-line tool: dispatches to subcommands, prints errors, sets exit codes.

#include <csignal>
#include <cstdio>
#include <exception>
#include <iostream>
#include <string>
#include <vector>

#include "app/commands.h"
#include "app/progress_bar.h"
#include "core/error.h"

namespace confluent::app {
namespace {

std::vector<CommandSpec> AllCommands() {
  return {
      MakeDemoCommand(),
      MakeCaptureInfoCommand(),
      MakeCalibConvertCommand(),
      MakeCalibCheckCommand(),
      MakeCalibrateCommand(),
      MakeMeshInfoCommand(),
      MakeRenderInfoCommand(),
      MakeSynthCommand(),
      MakeSilhouettesCommand(),
      MakeAnimateCommand(),
      MakeTrackCommand(),
      MakeCorrespondCommand(),
      MakeRunCommand(),
      MakeEvaluateCommand(),
      MakeViewCommand(),
      MakeRenderCommand(),
      MakeExportCommand(),
  };
}

void PrintOverview(const std::vector<CommandSpec>& commands) {
  std::printf(
      "confluent %s: multi-view markerless human capture and 3D video\n\n"
      "usage: confluent <command> [options]     (confluent <command> --help for details)\n\n"
      "commands:\n",
      CONFLUENT_VERSION);
  for (const auto& command : commands) std::printf("  %-18s %s\n", command.name.c_str(), command.summary.c_str());
}

// The command whose (one- or two-word) name matches the start of `args`, longest first.
const CommandSpec* FindCommand(const std::vector<CommandSpec>& commands, const std::vector<std::string>& args,
                               std::size_t* words) {
  const CommandSpec* best = nullptr;
  for (const auto& command : commands) {
    const bool two_words = command.name.find(' ') != std::string::npos;
    const std::string candidate = two_words && args.size() >= 2 ? args[0] + " " + args[1] : args[0];
    if (candidate == command.name && (best == nullptr || command.name.size() > best->name.size())) {
      best = &command;
      *words = two_words ? 2 : 1;
    }
  }
  return best;
}

int Main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  const std::vector<CommandSpec> commands = AllCommands();
  if (args.empty() || args[0] == "--help" || args[0] == "-h" || args[0] == "help") {
    PrintOverview(commands);
    return args.empty() ? 2 : 0;
  }
  if (args[0] == "--version") {
    std::printf("confluent %s\n", CONFLUENT_VERSION);
    return 0;
  }
  std::size_t words = 0;
  const CommandSpec* command = FindCommand(commands, args, &words);
  if (command == nullptr) {
    // A group name alone ("calib") lists its subcommands.
    bool group = false;
    for (const auto& candidate : commands)
      if (candidate.name.rfind(args[0] + " ", 0) == 0) {
        if (!group) std::fprintf(stderr, "confluent %s: choose a subcommand:\n", args[0].c_str());
        std::fprintf(stderr, "  %-18s %s\n", candidate.name.c_str(), candidate.summary.c_str());
        group = true;
      }
    if (!group) std::fprintf(stderr, "confluent: unknown command '%s' (see confluent --help)\n", args[0].c_str());
    return 2;
  }
  std::vector<std::string> rest(args.begin() + words, args.end());
  for (const auto& arg : rest)
    if (arg == "--help" || arg == "-h") {
      std::printf("%s", HelpText(*command).c_str());
      return 0;
    }
  ProgressBar bar;
  Context context;
  context.make_progress = [&bar]() { return bar.AsCallback(); };
  try {
    const ParsedArgs parsed = ParseArgs(*command, rest);
    const int status = command->run(parsed, context);
    bar.Finish();
    return status;
  } catch (const UsageError& error) {
    bar.Finish();
    std::fprintf(stderr, "confluent %s: %s\n", command->name.c_str(), error.what());
    return 2;
  } catch (const std::exception& error) {
    bar.Finish();
    std::fprintf(stderr, "confluent %s: error: %s\n", command->name.c_str(), error.what());
    return 1;
  }
}

}  // namespace
}  // namespace confluent::app

int main(int argc, char** argv) {
  std::setvbuf(stdout, nullptr, _IOLBF, 0);  // keep stdout lines in order with the progress on stderr
  // A file-size limit (ulimit -f) then fails the write with EFBIG, which is reported with the
  // file's name, instead of killing the process with SIGXFSZ.
  std::signal(SIGXFSZ, SIG_IGN);
  return confluent::app::Main(argc, argv);
}
