# Shared by the scripts in this folder: set-up (Debian packages + build). Sourced, not run.
set -euo pipefail

LIVO_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
LIVO_BUILD="${LIVO_BUILD:-$LIVO_ROOT/build}"
LIVO_JOBS="${LIVO_JOBS:-2}"

# Debian bookworm packages. LIVO_DEMO_PACKAGES build and run the README demo (scripts/run-demo: livo-sim,
# livo-run, livo-eval, livo-report); lcm.pc needs libglib2.0-dev; libceres-dev: libs/loop's pose graph
# (every library is configured, also for the demo). LIVO_PACKAGES is everything else the
# suite builds, tests and inspects with (scripts/run-tests, scripts/setup):
#   libgtest-dev: the tests; liblcm-java, default-jdk-headless, libjchart2d-java: lcm-spy (scripts/livo-spy);
#   default-jre: AWT for lcm-spy's window (the headless JDK has none);
#   xvfb: an X server without a screen for the tests that open windows (xauth: for xvfb-run;
#   libgl1-mesa-dri: Mesa's software OpenGL, which VTK renders with under Xvfb); libpcl-dev brings PCL's
#   visualisation module (VTK) for livo-viewer;
#   librosbag-storage-dev, libsensor-msgs-dev: `livo-convert rosbag` and its tests;
#   libroscpp-dev, libnav-msgs-dev, libtf2-msgs-dev, libdiagnostic-msgs-dev: livo-ros-bridge;
#   python3-roslaunch (roscore), python3-rosbag (rosbag play), python3-rostopic: the bridge's test;
#   iproute2: the tests' network namespaces; clang + libclang-rt-14-dev: the libFuzzer runs of tests/fuzz.
LIVO_DEMO_PACKAGES=(
  build-essential cmake pkg-config ccache git
  liblcm-dev liblcm-bin libglib2.0-dev
  libeigen3-dev libopencv-dev libpcl-dev liboctomap-dev libyaml-cpp-dev libceres-dev
  python3 python3-matplotlib
)
LIVO_PACKAGES=(
  "${LIVO_DEMO_PACKAGES[@]}"
  libgtest-dev liblcm-java default-jdk-headless default-jre libjchart2d-java xvfb xauth libgl1-mesa-dri
  librosbag-storage-dev libsensor-msgs-dev
  libroscpp-dev libnav-msgs-dev libtf2-msgs-dev libdiagnostic-msgs-dev
  python3-roslaunch python3-rosbag python3-rostopic
  iproute2
  clang libclang-rt-14-dev
)
# The targets of the demo (livo-report, a Python script, is copied into build/bin when CMake configures).
LIVO_DEMO_TARGETS=(livo-sim livo-run livo-eval)

log() { printf '[livo] %s\n' "$*" >&2; }

# Installs the packages named (default: LIVO_PACKAGES) that are missing (apt-get update first); does
# nothing when all are present.
livo_install_packages() {
  local wanted=("$@")
  [ ${#wanted[@]} -gt 0 ] || wanted=("${LIVO_PACKAGES[@]}")
  local missing=()
  for p in "${wanted[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if [ ${#missing[@]} -eq 0 ]; then
    log "all ${#wanted[@]} Debian packages present"
    return 0
  fi
  if [ "$(id -u)" -ne 0 ]; then
    log "missing packages: ${missing[*]}"
    log "run as root (or install them with: sudo apt-get install ${missing[*]})"
    exit 1
  fi
  log "installing ${#missing[@]} Debian packages: ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -q
  apt-get install -y -q --no-install-recommends "${missing[@]}"
}

# Configures (Release; extra arguments go to cmake) and builds everything with $LIVO_JOBS jobs; ccache
# is picked up by CMake when installed.
livo_build() {
  livo_configure "$@"
  livo_build_targets
}

livo_configure() {
  log "configuring $LIVO_BUILD"
  mkdir -p "$LIVO_BUILD"
  cmake -S "$LIVO_ROOT" -B "$LIVO_BUILD" -DCMAKE_BUILD_TYPE=Release "$@" >"$LIVO_BUILD/configure.log" 2>&1 ||
    { cat "$LIVO_BUILD/configure.log" >&2; log "cmake configure failed"; exit 1; }
}

# Builds the named targets (none: all) of the configured build tree.
livo_build_targets() {
  local what="everything" args=()
  if [ $# -gt 0 ]; then
    what="$*"
    args=(--target "$@")
  fi
  log "building $what with -j$LIVO_JOBS (log: $LIVO_BUILD/build.log)"
  local start=$SECONDS
  if ! cmake --build "$LIVO_BUILD" -j"$LIVO_JOBS" "${args[@]}" >"$LIVO_BUILD/build.log" 2>&1; then
    grep -E "error|Error" -A5 "$LIVO_BUILD/build.log" | head -60 >&2
    log "build failed (full log: $LIVO_BUILD/build.log)"
    exit 1
  fi
  log "build done in $((SECONDS - start)) s"
}

# Everything: all packages, every target (tests, fuzz targets, livo-ros-bridge).
livo_setup() {
  livo_install_packages
  livo_build "$@"
}

# The demo only: its packages and its binaries with their libraries (no tests, no fuzz targets).
livo_setup_demo() {
  livo_install_packages "${LIVO_DEMO_PACKAGES[@]}"
  livo_configure
  livo_build_targets "${LIVO_DEMO_TARGETS[@]}"
}
