#include "core/system/errno_text.h"

#include <array>
#include <cstring>

namespace canalid::core {

std::string ErrnoText(int errnum) {
  std::array<char, 256> buffer{};
  // GNU strerror_r: returns the message, either a static string or one written into buffer.
  return ::strerror_r(errnum, buffer.data(), buffer.size());
}

}  // namespace canalid::core
