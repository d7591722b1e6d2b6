#!/usr/bin/env bash
# Installs every Debian package omnislam needs to build, test and run (Debian bookworm).
# Idempotent: packages already present are skipped quickly. Needs root (or sudo).
set -euo pipefail

PKGS=(
  build-essential cmake pkg-config
  liblcm-dev liblcm-bin liblcm-java libglib2.0-dev   # LCM 1.3.1: library, lcm-gen/logger/spy, Java jar
  default-jdk-headless libjchart2d-java               # javac for the types jar; lcm-spy's viewer needs jchart2d
  default-jre                                         # lcm-spy is a Swing window: AWT's X11 library
  libeigen3-dev                                       # core maths
  libceres-dev                                        # Ceres Solver 2.1: the smoothing back end's least squares
  libopencv-dev                                       # image processing, rendering, image I/O
  libopencv-contrib-dev                               # cv::omnidir (ccalib): calibration tool, model checks
  libjpeg-dev                                         # libjpeg (OpenCV's): JPEG decoding that reports damaged data
  libyaml-cpp-dev                                     # world / config files
  libpugixml-dev                                      # OpenCV XML calibration files (OpenCV 4.6's parser crashes)
  libcli11-dev                                        # command-line flags
  libgtest-dev libgmock-dev googletest                # unit and integration tests
  libbenchmark-dev                                    # bench/
  xvfb xauth x11-apps imagemagick                     # headless lcm-spy check and its screenshot
  python3                                             # small test helpers
  clang-format                                        # scripts/format.sh: the style check CI runs
  clang-14                                            # scripts/fuzz.sh: the libFuzzer build (build-fuzz/)
  libclang-rt-14-dev                                  # libFuzzer and the sanitizer runtimes for clang-14
  iproute2                                            # ip: check-multicast.sh adds a multicast route
)

missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PKGS[@]} packages present"
  exit 0
fi
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || {
    echo "install-deps: missing ${missing[*]}; installing them needs root, and sudo is not installed:" >&2
    echo "install-deps: run 'apt-get install ${missing[*]}' as root, then this again" >&2
    exit 1
  }
  SUDO="sudo"
fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install-deps: done"
