// Fuzz targets over everything that reads bytes from outside: every LCM message decoder + validator +
// conversion (fuzzMessages), the YAML config loader with every section loader (fuzzConfig) and the map
// server's map files (fuzzMapFile). Each returns normally for every input; a rejected input must come
// with a non-empty error message (else the target aborts, which the fuzzer reports as a crash).
//
// Built twice: with clang and libFuzzer (+ ASan/UBSan) by tests/fuzz/CMakeLists.txt (scripts/fuzz and
// a short run in the tests), and with the normal build for test_io_fuzz, which replays the seeds and
// seeded mutations of them through the same functions.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace livo::fuzz {

/// First byte selects the message type (modulo the type count), the rest is the encoded message.
int fuzzMessages(const std::uint8_t* data, std::size_t size);
/// The bytes are a YAML document loaded as a rig config by every section loader.
int fuzzConfig(const std::uint8_t* data, std::size_t size);
/// The bytes are a map file (map_file.hpp).
int fuzzMapFile(const std::uint8_t* data, std::size_t size);

/// How many inputs the targets accepted and rejected (with a reason) since the last reset: test_io_fuzz's
/// replay checks that its mutations reach both outcomes (a replay that only ever rejects tests one check).
struct Outcomes {
  std::size_t accepted = 0, rejected = 0;
};
Outcomes& outcomes();

/// Valid inputs for a target ("messages", "config", "mapfile"): names and bytes.
std::vector<std::pair<std::string, std::vector<std::uint8_t>>> seeds(const std::string& target);

}  // namespace livo::fuzz
