#include "core/error.h"

#include <sstream>

namespace confluent {

void RequireOption(bool ok, const std::string& field, double value, const std::string& rule) {
  if (ok) return;
  std::ostringstream message;
  message << field << " = " << value << ": must be " << rule;
  throw UsageError(message.str());
}

void RequireOption(bool ok, const std::string& field, std::initializer_list<double> value, const std::string& rule) {
  if (ok) return;
  std::ostringstream message;
  message << field << " = (";
  const char* separator = "";
  for (double component : value) {
    message << separator << component;
    separator = ", ";
  }
  message << "): must be " << rule;
  throw UsageError(message.str());
}

void RequireOptions(bool ok, const std::string& field_a, double a, const std::string& field_b, double b,
                    const std::string& rule) {
  if (ok) return;
  std::ostringstream message;
  message << field_a << " = " << a << " and " << field_b << " = " << b << ": must be " << rule;
  throw UsageError(message.str());
}

}  // namespace confluent
