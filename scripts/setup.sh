#!/usr/bin/env bash
# Idempotent project setup (`make setup`):
#   1. .venv/ with the pinned wheels (ROS 2 Jazzy from PyPI, MuJoCo, Pinocchio, Ruckig, ...);
#   2. the interface packages under interfaces/ built with colcon into install/, each only where
#      no package of that name is importable;
#   3. this ament_python package built with colcon (--symlink-install) into install/, so that
#      install/ur_sim_driver/lib/ur_sim_driver/<exe> and the ament index entry exist for `ros2 run`;
#   4. Debian's headless-capable chromium for the studio's browser tests, if missing (apt-get, as root).
# A second run only checks stamps and finishes in seconds.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
VENV="$ROOT/.venv"
STAMPS="$VENV/.stamps"
log() { printf '[setup] %s\n' "$*"; }

pick_python() {
  if [ -n "${PYTHON:-}" ]; then echo "$PYTHON"; return; fi
  for c in python3 python3.13 python3.12 python3.11 python3.10; do
    if command -v "$c" >/dev/null 2>&1 && "$c" -c 'import sys; sys.exit(not ((3, 10) <= sys.version_info[:2] <= (3, 13)))'; then
      echo "$c"; return
    fi
  done
  echo "error: need CPython 3.10 to 3.13 (set PYTHON=/path/to/python3.X)" >&2; exit 1
}

# Build tools for the IDL build: a C/C++ compiler, cmake, and this Python's headers.
ensure_build_tools() {
  local py="$1" missing=()
  command -v cmake >/dev/null 2>&1 || missing+=(cmake)
  command -v c++ >/dev/null 2>&1 || missing+=(g++)
  command -v make >/dev/null 2>&1 || missing+=(make)
  "$py" -c 'import sysconfig, os, sys; sys.exit(not os.path.exists(os.path.join(sysconfig.get_paths()["include"], "Python.h")))' \
    || missing+=("python3-dev")
  [ ${#missing[@]} -eq 0 ] && return 0
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    log "installing build tools with apt-get: ${missing[*]}"
    DEBIAN_FRONTEND=noninteractive apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" >/dev/null
  else
    echo "error: missing build tools: ${missing[*]}. Install them (e.g. sudo apt-get install ${missing[*]}) and rerun make setup." >&2
    exit 1
  fi
}

# The studio's browser tests drive Debian's chromium through Playwright (which cannot download a browser here).
# Not needed to run anything else, so a missing browser without root is a note, not an error.
ensure_chromium() {
  command -v chromium >/dev/null 2>&1 && return 0
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    log "installing chromium with apt-get (for the studio's browser tests)"
    DEBIAN_FRONTEND=noninteractive apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends chromium fonts-dejavu-core >/dev/null
  else
    log "note: no chromium; the studio's browser tests need it (sudo apt-get install chromium)"
  fi
}

hash_of() { cat "$@" | sha256sum | cut -c1-16; }

PY="$(pick_python)"
if [ ! -x "$VENV/bin/python" ]; then
  log "creating .venv with $("$PY" --version)"
  "$PY" -m venv "$VENV"
fi
mkdir -p "$STAMPS"
VPY="$VENV/bin/python"

# --- 1. wheels ---------------------------------------------------------------------------------
req_hash="$(hash_of requirements.txt constraints.txt)"
if [ ! -f "$STAMPS/wheels-$req_hash" ]; then
  log "installing pinned wheels into .venv"
  constraint_args=()
  if "$VPY" -c 'import sys; sys.exit(sys.version_info[:2] < (3, 11))'; then constraint_args=(-c constraints.txt); fi
  "$VPY" -m pip install -q --disable-pip-version-check -r requirements.txt "${constraint_args[@]}" 2>&1 \
    | grep -v '^WARNING: Location' || true
  "$VPY" -m pip check >/dev/null 2>&1 || log "note: pip check reports conflicts (see '.venv/bin/pip check')"
  # The ROS wheels' CMake exports hard-code the include paths of the machine that built them;
  # point them at this interpreter so that interface packages can be built against the venv.
  py_inc="$("$VPY" -c 'import sysconfig; print(sysconfig.get_paths()["include"])')"
  np_inc="$("$VPY" -c 'import numpy; print(numpy.get_include())')"
  { grep -rlE --include='*.cmake' '/opt/python/cp3[0-9]+-cp3[0-9]+' "$VENV/share" 2>/dev/null || true; } | while read -r f; do
    sed -i -E "s#/opt/python/cp3[0-9]+-cp3[0-9]+/include/python3\.[0-9]+#${py_inc}#g; s#/opt/python/cp3[0-9]+-cp3[0-9]+/lib/python3\.[0-9]+/site-packages/numpy/_core/include#${np_inc}#g" "$f"
  done
  touch "$VENV/COLCON_IGNORE"
  rm -f "$STAMPS"/wheels-*
  touch "$STAMPS/wheels-$req_hash"
fi

# shellcheck source=env.bash
source "$ROOT/scripts/env.bash"

# --- 2. interface packages --------------------------------------------------------------------
# Every package under interfaces/ (control_msgs, ur_msgs, ur_dashboard_msgs, controller_manager_msgs,
# tf2_msgs) is built from our IDL only where no package of that name is importable (e.g. from a ROS 2
# install). One colcon call builds all missing ones; a stamp per package triggers a rebuild when its IDL
# changes.
iface_pkgs=()
for d in "$ROOT"/interfaces/*/; do
  [ -f "$d/package.xml" ] && iface_pkgs+=("$(basename "$d")")
done
for pkg in "${iface_pkgs[@]}"; do
  h="$(hash_of "interfaces/$pkg"/*/* "interfaces/$pkg/CMakeLists.txt" "interfaces/$pkg/package.xml")"
  if [ -f "$ROOT/install/$pkg/share/$pkg/package.xml" ] && [ ! -f "$STAMPS/iface-$pkg-$h" ]; then
    log "interfaces/$pkg changed: rebuilding"
    rm -rf "$ROOT/build/$pkg" "$ROOT/install/$pkg"
  fi
done
# shellcheck disable=SC2207
missing=($(python - "${iface_pkgs[@]}" <<'PYEOF'
import importlib
import sys
for name in sys.argv[1:]:
    try:
        importlib.import_module(name + '.msg')
    except ImportError:
        print(name)
PYEOF
))
if [ ${#missing[@]} -gt 0 ]; then
  ensure_build_tools "$VPY"
  mkdir -p "$ROOT/log"
  log "not importable: ${missing[*]}; building them from interfaces/ with colcon (a few minutes)"
  colcon --log-base "$ROOT/log" build --base-paths "$ROOT/interfaces" --build-base "$ROOT/build" \
    --install-base "$ROOT/install" --packages-select "${missing[@]}" \
    --cmake-args -DBUILD_TESTING=OFF -DPython3_EXECUTABLE="$VPY" --event-handlers console_cohesion- \
    > "$ROOT/log/interfaces_build.txt" 2>&1 || { tail -40 "$ROOT/log/interfaces_build.txt"; exit 1; }
  for pkg in "${missing[@]}"; do
    h="$(hash_of "interfaces/$pkg"/*/* "interfaces/$pkg/CMakeLists.txt" "interfaces/$pkg/package.xml")"
    rm -f "$STAMPS/iface-$pkg-"*
    touch "$STAMPS/iface-$pkg-$h"
  done
  source "$ROOT/scripts/env.bash"
fi

# --- 3. this package ---------------------------------------------------------------------------
pkg_hash="$(hash_of setup.py setup.cfg package.xml)"
if [ ! -f "$STAMPS/package-$pkg_hash" ] || [ ! -x "$ROOT/install/ur_sim_driver/lib/ur_sim_driver/ur_sim" ]; then
  log "building ur_sim_driver with colcon (--symlink-install)"
  mkdir -p "$ROOT/log"
  colcon --log-base "$ROOT/log" build --base-paths "$ROOT" --build-base "$ROOT/build" \
    --install-base "$ROOT/install" --packages-select ur_sim_driver --symlink-install \
    > "$ROOT/log/ur_sim_driver_build.txt" 2>&1 || { tail -40 "$ROOT/log/ur_sim_driver_build.txt"; exit 1; }
  rm -f "$STAMPS"/package-*
  touch "$STAMPS/package-$pkg_hash"
  source "$ROOT/scripts/env.bash"
fi

# --- 4. browser for the studio's tests ------------------------------------------------------------
ensure_chromium

python -c 'import rclpy, control_msgs.action, ur_msgs.srv, ur_dashboard_msgs.srv, controller_manager_msgs.srv, tf2_msgs.msg, ur_sim_driver, ur_glue_planner' \
  || { echo "error: the environment does not import; see log/" >&2; exit 1; }
log "ready: source scripts/env.bash"
