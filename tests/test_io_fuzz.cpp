// The fuzz targets of tests/fuzz (every message decoder + validator + conversion, the config loader,
// map files) replayed in the normal build: the valid seeds, then seeded random mutations of them (bit
// flips, interesting integers over count fields, truncation, duplication, insertion; for YAML also
// line and value mutations). Every input must be handled: accepted, or rejected with a message (the
// targets abort otherwise). Coverage-guided runs with libFuzzer + ASan/UBSan: tests/fuzz/CMakeLists.txt
// (a short run in ctest when clang's libFuzzer is installed) and scripts/fuzz (longer).
// livo-test-deps: livo_io livo_estimation livo_map livo_sensors
#include "fuzz/fuzz_targets.cpp"  // compiled into this test (the fuzzers compile it with clang)

#include <gtest/gtest.h>

#include <random>

using namespace livo;

namespace {

std::vector<std::uint8_t> mutate(std::vector<std::uint8_t> b, std::mt19937& rng) {
  std::uniform_int_distribution<int> op(0, 6), nops(1, 4);
  static const std::int32_t kInteresting[] = {0, -1, 1, 0x7fffffff, INT32_MIN, 1 << 20, 65535, 256, 12, -2};
  const int n = nops(rng);
  for (int k = 0; k < n; ++k) {
    if (b.empty()) b.push_back(0);
    std::uniform_int_distribution<std::size_t> at(0, b.size() - 1);
    switch (op(rng)) {
      case 0: b[at(rng)] ^= std::uint8_t(1u << (rng() % 8)); break;
      case 1: b[at(rng)] = std::uint8_t(std::array<int, 4>{0, 0xff, 0x7f, 0x80}[rng() % 4]); break;
      case 2: {  // a big-endian int32 (LCM's byte order) over 4 bytes: counts and sizes
        const std::size_t i = at(rng);
        const auto v = std::uint32_t(kInteresting[rng() % (sizeof(kInteresting) / sizeof(kInteresting[0]))]);
        for (int j = 0; j < 4 && i + std::size_t(j) < b.size(); ++j) b[i + std::size_t(j)] = std::uint8_t(v >> (24 - 8 * j));
        break;
      }
      case 3: b.resize(at(rng)); break;
      case 4: {
        const std::size_t i = at(rng), len = std::min<std::size_t>(b.size() - i, rng() % 64);
        b.insert(b.begin() + std::ptrdiff_t(i), b.begin() + std::ptrdiff_t(i), b.begin() + std::ptrdiff_t(i + len));
        break;
      }
      case 5: b.insert(b.begin() + std::ptrdiff_t(at(rng)), std::uint8_t(rng())); break;
      default: b.erase(b.begin() + std::ptrdiff_t(at(rng))); break;
    }
  }
  return b;
}

/// YAML-aware mutations: a value replaced by a hostile one, a line dropped or duplicated.
std::vector<std::uint8_t> mutateYaml(const std::vector<std::uint8_t>& in, std::mt19937& rng) {
  std::string t(in.begin(), in.end());
  static const char* kValues[] = {"nan", "-1", "1e400", "[", "{a: 1}", "[1, 2]", "''", "-.inf", "0", "99999999999"};
  std::vector<std::string> lines;
  std::stringstream ss(t);
  for (std::string l; std::getline(ss, l);) lines.push_back(l);
  if (lines.empty()) return in;
  std::uniform_int_distribution<std::size_t> at(0, lines.size() - 1);
  const std::size_t i = at(rng);
  switch (rng() % 3) {
    case 0: {
      const auto c = lines[i].find(':');
      if (c != std::string::npos) lines[i] = lines[i].substr(0, c + 1) + " " + kValues[rng() % 10];
      break;
    }
    case 1: lines.erase(lines.begin() + std::ptrdiff_t(i)); break;
    default: lines.insert(lines.begin() + std::ptrdiff_t(i), lines[i]); break;
  }
  std::string out;
  for (const auto& l : lines) out += l + "\n";
  return std::vector<std::uint8_t>(out.begin(), out.end());
}

void replay(const std::string& target, int (*fn)(const std::uint8_t*, std::size_t), int mutations_per_seed,
            bool yaml = false) {
  const auto seeds = fuzz::seeds(target);
  ASSERT_FALSE(seeds.empty());
  std::mt19937 rng(12345);
  std::size_t runs = 0;
  fuzz::outcomes() = {};
  for (const auto& [name, bytes] : seeds) {
    SCOPED_TRACE(name);
    fn(bytes.data(), bytes.size());
    for (int k = 0; k < mutations_per_seed; ++k) {
      const std::vector<std::uint8_t> m = yaml && k % 2 ? mutateYaml(bytes, rng) : mutate(bytes, rng);
      fn(m.data(), m.size());
      ++runs;
    }
  }
  // Every input returned (an unhandled one aborts the target); the mutations must reach both outcomes,
  // else the replay exercises one check only.
  const fuzz::Outcomes o = fuzz::outcomes();
  EXPECT_EQ(o.accepted + o.rejected, runs + seeds.size());
  EXPECT_GE(o.accepted, seeds.size());  // at least the valid seeds
  EXPECT_GT(o.rejected, runs / 10);
  std::cout << target << ": " << seeds.size() << " seeds, " << runs << " mutated inputs handled: " << o.accepted
            << " accepted, " << o.rejected << " rejected with a reason\n";
}

}  // namespace

TEST(Fuzz, SeedsAreValid) {
  // The message seeds must decode and convert (else the mutations would only test the first check).
  const MessageLimits lim;
  for (const auto& [name, bytes] : fuzz::seeds("messages")) {
    SCOPED_TRACE(name);
    ASSERT_GT(bytes.size(), 1u);
  }
  livo::imu_t m;
  const auto s = fuzz::seeds("messages");
  EXPECT_TRUE(decode(s[0].second.data() + 1, s[0].second.size() - 1, m, lim));
  for (const auto& [name, bytes] : fuzz::seeds("config")) {
    const std::string text(bytes.begin(), bytes.end());
    EXPECT_NO_THROW(ConfigFile::parse(text, name)) << name;
  }
  HybridMap map(HybridMapConfig{}, VoxelMapConfig{}, VisualMapConfig{});
  const auto mf = fuzz::seeds("mapfile");
  std::istringstream in(std::string(mf[0].second.begin(), mf[0].second.end()));
  const MapFileInfo info = loadMap(in, "seed", map);
  EXPECT_GT(info.planes, 0u);
  EXPECT_EQ(info.visual_points_local, 1u);
}

TEST(Fuzz, MessageDecodersHandleMutatedMessages) { replay("messages", fuzz::fuzzMessages, 3000); }
TEST(Fuzz, ConfigLoaderHandlesMutatedConfigs) { replay("config", fuzz::fuzzConfig, 1500, true); }
TEST(Fuzz, MapFileLoaderHandlesMutatedFiles) { replay("mapfile", fuzz::fuzzMapFile, 3000); }
