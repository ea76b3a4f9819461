#include "app/command_line.h"

#include <sstream>

#include "core/error.h"

namespace confluent::app {

std::string ParsedArgs::get(const std::string& name, const std::string& fallback) const {
  auto it = values_.find(name);
  return (it == values_.end() || it->second.empty()) ? fallback : it->second.back();
}

std::vector<std::string> ParsedArgs::get_all(const std::string& name) const {
  auto it = values_.find(name);
  return it == values_.end() ? std::vector<std::string>{} : it->second;
}

double ParsedArgs::get_double(const std::string& name, double fallback) const {
  if (!has(name)) return fallback;
  const std::string text = get(name);
  try {
    std::size_t used = 0;
    double value = std::stod(text, &used);
    if (used == text.size()) return value;
  } catch (const std::exception&) {
  }
  throw UsageError("--" + name + ": expected a number, got '" + text + "'");
}

int ParsedArgs::get_int(const std::string& name, int fallback) const {
  if (!has(name)) return fallback;
  const std::string text = get(name);
  try {
    std::size_t used = 0;
    int value = std::stoi(text, &used);
    if (used == text.size()) return value;
  } catch (const std::exception&) {
  }
  throw UsageError("--" + name + ": expected an integer, got '" + text + "'");
}

namespace {
const OptionSpec* FindOption(const CommandSpec& spec, const std::string& name) {
  for (const auto& option : spec.options)
    if (option.name == name) return &option;
  return nullptr;
}
}  // namespace

ParsedArgs ParseArgs(const CommandSpec& spec, const std::vector<std::string>& args) {
  ParsedArgs parsed;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    if (arg.size() > 2 && arg.compare(0, 2, "--") == 0) {
      std::string name = arg.substr(2);
      std::string value;
      bool inline_value = false;
      if (auto eq = name.find('='); eq != std::string::npos) {
        value = name.substr(eq + 1);
        name = name.substr(0, eq);
        inline_value = true;
      }
      const OptionSpec* option = FindOption(spec, name);
      if (option == nullptr)
        throw UsageError("confluent " + spec.name + ": unknown option --" + name + " (see --help)");
      if (option->value_name.empty()) {
        if (inline_value) throw UsageError("--" + name + " takes no value");
        value = "1";
      } else if (!inline_value) {
        if (i + 1 >= args.size()) throw UsageError("--" + name + " needs a value " + option->value_name);
        value = args[++i];
      }
      auto& slot = parsed.values_[name];
      if (!slot.empty() && !option->repeated) throw UsageError("--" + name + " given more than once");
      slot.push_back(value);
    } else {
      parsed.positionals_.push_back(arg);
    }
  }
  for (const auto& option : spec.options)
    if (option.required && !parsed.has(option.name))
      throw UsageError("confluent " + spec.name + ": missing --" + option.name + " " + option.value_name);
  const int count = static_cast<int>(parsed.positionals_.size());
  if (count < spec.min_positionals || count > spec.max_positionals)
    throw UsageError("usage: confluent " + spec.name + " " + spec.usage);
  return parsed;
}

std::string HelpText(const CommandSpec& spec) {
  std::ostringstream out;
  out << "usage: confluent " << spec.name << " " << spec.usage << "\n\n" << spec.summary << "\n";
  if (!spec.description.empty()) out << "\n" << spec.description << "\n";
  if (!spec.options.empty()) out << "\noptions:\n";
  for (const auto& option : spec.options) {
    std::string left = "  --" + option.name + (option.value_name.empty() ? "" : " " + option.value_name);
    if (left.size() < 30) left.resize(30, ' ');
    else left += "\n" + std::string(30, ' ');
    out << left << option.help << (option.repeated ? " (repeatable)" : "")
        << (option.required ? " (required)" : "") << "\n";
  }
  out << "  --help                      show this help\n";
  return out.str();
}

}  // namespace confluent::app
