#include "livo/process/cli.hpp"

#include "livo/common/worker_pool.hpp"
#include "livo/io/channels.hpp"

#include <string>

namespace livo {

const char* const kPrintConfigHelp =
    "print the effective configuration as YAML on stdout (every key this program reads, defaults filled "
    "in, command-line overrides applied) and exit; it loads back as a --config giving the same behaviour";

void addProcessOptions(CommandLine& cl, ProcessArgs& args) {
  cl.text("--config", &args.config, "CFG.yaml", "rig config (channels, sensor and module sections)").required();
  cl.text("--lcm-url", &args.lcm_url, "URL", "LCM URL").defaultText(std::string("$LCM_DEFAULT_URL, else ") + kDefaultLcmUrl);
  cl.number("--idle-exit", &args.idle_exit_s, "S",
            "exit as on SIGINT after S seconds without any message (0: never; for tests and batch runs)", 0.0)
      .unit("s");
  cl.flag("--print-config", &args.print_config, kPrintConfigHelp);
}

void addThreadsOption(CommandLine& cl, int* threads) {
  cl.integer("--threads", threads, "N",
             "threads of the per-frame loops (LiDAR association, photometric patches); the results are the same "
             "for every N",
             1, WorkerPool::kMaxThreads)
      .defaultText("the machine's cores, at most 4 (here " + std::to_string(defaultThreadCount()) + ")");
}

void checkSectionsUsed(const ConfigFile& file, const std::vector<std::string>& sections) {
  for (const std::string& key : file.unusedKeys())
    for (const std::string& sec : sections)
      if (key == sec || key.rfind(sec + ".", 0) == 0)
        throw ConfigError(file.name() + ": " + key + ": unknown key (not read by any module of this process)");
}

void printConfig(std::ostream& os, const std::string& program, const ConfigFile& file,
                 const std::string& command_line) {
  os << "# Effective configuration of " << program << " (--print-config): every key it reads, defaults filled in.\n";
  if (!command_line.empty()) os << "# Command-line settings, not config keys: " << command_line << "\n";
  os << file.effectiveYaml();
}

}  // namespace livo
