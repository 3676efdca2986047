#include "core/online/option_checks.h"

#include <sstream>
#include <stdexcept>

namespace canalid::core {

void ThrowOptionOutOfRange(std::string_view owner, std::string_view name, double value,
                           std::string_view range) {
  std::ostringstream message;
  message << owner << "." << name << " = " << value << " is out of range (allowed: " << range
          << ")";
  throw std::invalid_argument(message.str());
}

}  // namespace canalid::core
