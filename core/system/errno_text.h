#pragma once
#include <string>

namespace canalid::core {

/// The text of an errno value ("No such file or directory"), for error messages.  Safe to call
/// from any thread, unlike std::strerror; an unknown value gives "Unknown error N".
std::string ErrnoText(int errnum);

}  // namespace canalid::core
