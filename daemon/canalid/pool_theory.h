#pragma once
#include <string>

#include "core/hydraulics/idz_theory.h"

namespace canalid::cli {

/// The IDZ theory of one pool of a canal file (canalsim's TOML) at `flow_m3s`.
/// @throws InputError naming the file, the pool (with the pools there are) or the flow.
core::IdzTheory PoolTheory(const std::string& canal_file, const std::string& pool, double flow_m3s);

}  // namespace canalid::cli
