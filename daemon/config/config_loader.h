#pragma once
#include <string>
#include <string_view>

#include "core/toml/toml_reader.h"
#include "daemon/config/daemon_config.h"

namespace canalid::daemon {

/// One problem of a configuration file, printed as
///   file:line:column: key.path: message
/// (line and column 1-based; the key's or its value's position, or its table's when it is missing;
/// path "" for a syntax error).
using ConfigIssue = core::TomlIssue;

/// Every problem of a configuration at once, sorted by position. what() is all of them, one per
/// line.
using ConfigError = core::TomlError;

/// Parses canalidd's TOML configuration (docs/configuration.md) strictly: unknown keys and
/// tables, wrong types, missing required keys, keys of another transport or mode, and every
/// problem of core::Validate are reported together.  `name` is the file name used in messages.
/// @throws ConfigError with every problem (a TOML syntax error is reported alone).
config::DaemonConfig ParseDaemonConfig(std::string_view text, const std::string& name);

/// Reads and parses the file `path`.  @throws ConfigError (also when it cannot be read).
config::DaemonConfig LoadDaemonConfig(const std::string& path);

/// The effective configuration as TOML, every key written with its value (defaults included),
/// numbers in their shortest exact form, so that ParseDaemonConfig(RenderDaemonConfig(c)) == c for
/// every c that ParseDaemonConfig returns (fields of the other transport or experiment mode are
/// not written: they keep their defaults).  Published on LCM at start, parsed again by
/// `canalid replay`.
std::string RenderDaemonConfig(const config::DaemonConfig& config);

}  // namespace canalid::daemon
