#include "core/error.h"

#include <sstream>

namespace confluent {

void RequireOption(bool ok, const std::string& field, double value, const std::string& rule) {
  if (ok) return;
  std::ostringstream message;
  message << field << " = " << value << ": must be " << rule;
  throw UsageError(message.str());
}

}  // namespace confluent
