#!/usr/bin/env bash
# Installs the Debian packages tripodal needs to build, test and benchmark. Idempotent: packages
# already present are left alone and apt is not touched at all when nothing is missing.
#
#   scripts/install-deps.sh [GROUP...]   also the packages of the hardening scripts that need them:
#     fuzz   clang and its runtime (libFuzzer, ASan, UBSan), for scripts/fuzz.sh
#     tidy   clang-tidy and clang-format (with clang-format-diff), for scripts/tidy.sh and
#            scripts/format.sh
#     browser  headless Chromium and Selenium, for the monitor's browser tests
#              (cmake -DTRIPODAL_BROWSER_TESTS=ON; ctest -L browser)
#     ros2-peer  Fast DDS (ROS 2's default middleware), the independent peer of the ROS 2 graph
#                tests (tests/dds/ros2_peer_test.cpp; without it they are not built)
#     netns  nftables and iproute2, for scripts/netns_fleet.sh (a fleet across network namespaces)
#     perf   valgrind (callgrind), for the instruction-count guard scripts/instructions.sh; stress-ng, the
#            CPU load beside the loop jitter figures (docs/performance.md)
#   (ThreadSanitizer, scripts/tsan.sh, needs nothing more: libtsan2 comes with g++.)
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config
  ccache  # every tree compiles through it (CMakeLists.txt, TRIPODAL_CCACHE)
  libeigen3-dev libyaml-cpp-dev libspdlog-dev
  libfmt-dev nlohmann-json3-dev libcli11-dev
  libtinyxml2-dev  # the net loaders read XML with it
  catch2 libbenchmark-dev
  graphviz libxml2-utils
  zlib1g-dev
  libzstd-dev liblz4-dev libsqlite3-dev  # rosbag2 bags: MCAP chunks and .db3 storage (docs/rosbag.md)
  libpng-dev  # tripodal-coverage-eval reads the ipa floor plans (docs/coverage.md)
)
# The monitor: Graphviz's library lays out the nets it draws (src/monitor/net_drawing.cpp); its
# protocol test (tests/monitor/protocol_test.py) is a WebSocket client in Python.
packages+=(libgraphviz-dev python3 python3-websockets)
# The docs' checks (scripts/doc_blocks.py parses the YAML blocks).
packages+=(python3-yaml)
# Distribution over DDS (tripodal::dds, docs/distribution.md): Eclipse Cyclone DDS and its IDL
# compiler idlc, which generates the message types at build time. Without them the build leaves
# the dds area out (TRIPODAL_DDS=OFF).
packages+=(cyclonedds-dev cyclonedds-tools)
# The HRI (tripodal::hri, docs/hri.md): Xapian ranks the knowledge base (BM25, English stemming).
packages+=(libxapian-dev)
# Its lexicon (src/hri/lexicon.cpp): WordNet's synonyms and base forms, and an English word list so
# typo correction leaves English words alone. Without them the HRI matches words as the base has them.
packages+=(wordnet-base wamerican)
# Its voice (optional, TRIPODAL_VOICE): espeak-ng synthesises, pocketsphinx recognises with the
# US English acoustic model.
packages+=(libespeak-ng-dev libpocketsphinx-dev pocketsphinx-en-us)
# The spoken corpus's room noise (tests/hri/spoken_corpus_test.cpp): sox makes it; without sox the
# noisy part of that test is skipped with a warning.
packages+=(sox)
# Its live audio (optional, TRIPODAL_ALSA): microphone and speaker through ALSA.
packages+=(libasound2-dev)

for group in "$@"; do
  case $group in
    # libclang-rt-14-dev holds libFuzzer itself (libclang_rt.fuzzer), which -fsanitize=fuzzer links.
    fuzz) packages+=(clang libclang-rt-14-dev) ;;
    tidy) packages+=(clang-tidy clang-format) ;;
    browser) packages+=(chromium chromium-driver python3-selenium) ;;
    ros2-peer) packages+=(libfastrtps-dev libfastcdr-dev) ;;
    perf) packages+=(valgrind stress-ng) ;;
    # scripts/netns_fleet.sh: a fleet across network namespaces, nftables for loss and partitions.
    netns) packages+=(nftables iproute2) ;;
    *) echo "install-deps: unknown group '$group' (expected fuzz, tidy, browser, ros2-peer, perf or netns)" >&2; exit 2 ;;
  esac
done

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
