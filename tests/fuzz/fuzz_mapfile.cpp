// libFuzzer entry point of fuzz_targets.hpp: fuzzMapFile.
#include "fuzz_targets.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return livo::fuzz::fuzzMapFile(data, size);
}
