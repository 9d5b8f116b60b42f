// fuzz_seeds TARGET DIR: writes the valid seed inputs of a fuzz target (messages, config, mapfile) into
// DIR, the starting corpus of the libFuzzer runs.
#include "fuzz_targets.hpp"

#include <filesystem>
#include <fstream>
#include <iostream>

int main(int argc, char** argv) {
  if (argc != 3) {
    std::cerr << "usage: fuzz_seeds messages|config|mapfile DIR\n";
    return 2;
  }
  try {
    std::filesystem::create_directories(argv[2]);
    for (const auto& [name, bytes] : livo::fuzz::seeds(argv[1])) {
      std::ofstream(std::string(argv[2]) + "/seed_" + name, std::ios::binary)
          .write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
    }
  } catch (const std::exception& e) {
    std::cerr << "fuzz_seeds: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
