#include "livo/cli/command_line.hpp"

#include "livo_cli_version.hpp"

namespace livo {

const char* projectVersion() { return LIVO_PROJECT_VERSION; }

}  // namespace livo
