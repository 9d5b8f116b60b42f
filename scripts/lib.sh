# Shared by the scripts in this folder: set-up (Debian packages + build). Sourced, not run.
set -euo pipefail

LIVO_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
LIVO_BUILD="${LIVO_BUILD:-$LIVO_ROOT/build}"
LIVO_JOBS="${LIVO_JOBS:-2}"

# Debian bookworm packages the suite needs to build, test and inspect (lcm.pc needs libglib2.0-dev).
# librosbag-storage-dev: `livo-convert rosbag` (optional at build time); libsensor-msgs-dev: its tests.
# clang + libclang-rt-14-dev: the libFuzzer runs of tests/fuzz (ctest, scripts/fuzz).
# libpcl-dev brings PCL's visualisation module (VTK) for livo-viewer; xvfb: an X server without a screen
# for the tests that open windows (xauth: for xvfb-run; libgl1-mesa-dri: Mesa's software OpenGL, which
# VTK renders with under Xvfb); default-jre: AWT for lcm-spy's window (the headless JDK has none).
LIVO_PACKAGES=(
  build-essential cmake pkg-config ccache git
  liblcm-dev liblcm-bin liblcm-java libglib2.0-dev
  libeigen3-dev libopencv-dev libpcl-dev liboctomap-dev libyaml-cpp-dev libgtest-dev
  default-jdk-headless default-jre libjchart2d-java xvfb xauth libgl1-mesa-dri
  librosbag-storage-dev libsensor-msgs-dev
  iproute2 python3 python3-matplotlib
  clang libclang-rt-14-dev
)

log() { printf '[livo] %s\n' "$*" >&2; }

# Installs the packages that are missing (apt-get update first); does nothing when all are present.
livo_install_packages() {
  local missing=()
  for p in "${LIVO_PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if [ ${#missing[@]} -eq 0 ]; then
    log "all ${#LIVO_PACKAGES[@]} Debian packages present"
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

# Configures (Release) and builds with $LIVO_JOBS jobs; ccache is picked up by CMake when installed.
livo_build() {
  log "configuring $LIVO_BUILD"
  mkdir -p "$LIVO_BUILD"
  cmake -S "$LIVO_ROOT" -B "$LIVO_BUILD" -DCMAKE_BUILD_TYPE=Release "$@" >"$LIVO_BUILD/configure.log" 2>&1 ||
    { cat "$LIVO_BUILD/configure.log" >&2; log "cmake configure failed"; exit 1; }
  log "building with -j$LIVO_JOBS (log: $LIVO_BUILD/build.log)"
  local start=$SECONDS
  if ! cmake --build "$LIVO_BUILD" -j"$LIVO_JOBS" >"$LIVO_BUILD/build.log" 2>&1; then
    grep -E "error|Error" -A5 "$LIVO_BUILD/build.log" | head -60 >&2
    log "build failed (full log: $LIVO_BUILD/build.log)"
    exit 1
  fi
  log "build done in $((SECONDS - start)) s"
}

livo_setup() {
  livo_install_packages
  livo_build "$@"
}
