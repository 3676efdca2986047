#pragma once
// The command key, channel and daemon clock of lcm_command_fuzz.cc, shared with lcm_seeds.cc,
// which signs the seed commands with them.
#include <cstdint>
#include <vector>

namespace canalid::fuzz {

inline const std::vector<uint8_t> kCommandKey = {'f', 'u', 'z', 'z', '-', 'k', 'e', 'y'};
inline constexpr const char* kCommandChannel = "CANALID_COMMAND";
inline constexpr int64_t kNowUs = 1763700000400000;

}  // namespace canalid::fuzz
