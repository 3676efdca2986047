#pragma once
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "core/daemon_config.h"

namespace canalid::daemon {

/// One problem of a configuration file, printed as
///   file:line:column: key.path: message
/// (line and column 1-based; the key's or its value's position, or its table's when it is missing).
struct ConfigIssue {
  std::string file;
  int line = 1;
  int column = 1;
  std::string path;  ///< TOML key path, 0-based array indices: "channel[2].plc"; "" for syntax
  std::string message;
  std::string ToString() const;
};

/// Every problem of a configuration at once, sorted by position. what() is all of them, one per
/// line.
class ConfigError : public std::runtime_error {
 public:
  explicit ConfigError(std::vector<ConfigIssue> issues);
  const std::vector<ConfigIssue>& issues() const { return issues_; }

 private:
  std::vector<ConfigIssue> issues_;
};

/// Parses canalidd's TOML configuration (docs/configuration.md) strictly: unknown keys and
/// tables, wrong types, missing required keys, keys of another transport or mode, and every
/// problem of core::Validate are reported together.  `name` is the file name used in messages.
/// @throws ConfigError with every problem (a TOML syntax error is reported alone).
core::DaemonConfig ParseDaemonConfig(std::string_view text, const std::string& name);

/// Reads and parses the file `path`.  @throws ConfigError (also when it cannot be read).
core::DaemonConfig LoadDaemonConfig(const std::string& path);

/// The effective configuration as TOML, every key written with its value (defaults included),
/// numbers in their shortest exact form, so that ParseDaemonConfig(RenderDaemonConfig(c)) == c for
/// every c that ParseDaemonConfig returns (fields of the other transport or experiment mode are
/// not written: they keep their defaults).  Published on LCM at start, parsed again by
/// `canalid replay`.
std::string RenderDaemonConfig(const core::DaemonConfig& config);

}  // namespace canalid::daemon
