#pragma once
#include <string>

#include "core/hydraulics/idz_theory.h"
#include "sim/canal.h"

namespace canalid::cli {

/// The geometry of a canal file's pool, as the IDZ theory takes it.
core::PoolGeometry GeometryOf(const sim::Pool& pool);

/// The IDZ theory of `pool` (of the canal file `canal_file`, for messages) at `flow_m3s`.
/// @throws InputError naming the file, the pool and the flow.
core::IdzTheory TheoryOf(const std::string& canal_file, const sim::Pool& pool, double flow_m3s);

/// The IDZ theory of one pool of a canal file (canalsim's TOML) at `flow_m3s`.
/// @throws InputError naming the file, the pool (with the pools there are) or the flow.
core::IdzTheory PoolTheory(const std::string& canal_file, const std::string& pool, double flow_m3s);

/// "--pool 'P' is not a pool of FILE (pools: ...)".
std::string NotAPoolMessage(const sim::Canal& canal, const std::string& canal_file,
                            const std::string& pool);

}  // namespace canalid::cli
