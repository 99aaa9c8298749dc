#!/usr/bin/env bash
# Build the message packages under interfaces/ into the venv VENV.
#
#   interfaces/build.sh VENV [PACKAGE...]   (default: every interfaces/*/package.xml)
#                                           (PYTHON=python3 creates VENV if it does not exist)
#
# The PyPI ROS 2 Jazzy wheels have neither tf2_msgs (TFMessage) nor control_msgs
# (FollowJointTrajectory, GripperCommand). This generates each package from its definitions in
# interfaces/PACKAGE with the PyPI rosidl tooling (requirements-build.txt), cmake and a C/C++
# compiler, and installs it into VENV, which the ROS wheels already use as their prefix (python
# package in site-packages, libraries in lib/, ament index and CMake config in share/). The
# installed package is the cache: VENV/.PACKAGE holds the hash of the files of interfaces/PACKAGE
# it was built from, and a run with the same files builds nothing. Where the package is importable
# from elsewhere (a sourced ROS 2 Jazzy) or /opt/ros/jazzy has it, nothing is built either.
set -euo pipefail
VENV=${1:?usage: interfaces/build.sh VENV [PACKAGE...]}
shift
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
PY=$VENV/bin/python
if [ $# -gt 0 ]; then
    PACKAGES=("$@")
else
    mapfile -t PACKAGES < <(cd "$HERE" && ls -d -- */package.xml | cut -d/ -f1)
fi

if [ ! -x "$PY" ]; then
    "${PYTHON:-python3}" -m venv "$VENV" || { echo "python3 -m venv failed: apt-get install python3-venv" >&2; exit 1; }
fi
LOCK=$HERE/../requirements-lock.txt                 # the versions the suite passed with
"$PY" -m pip install --quiet -r "$HERE/../requirements-build.txt" $([ -f "$LOCK" ] && echo -c "$LOCK")
PREFIX=$(cd "$VENV" && pwd)

# Succeeds if PACKAGE's Python modules (PACKAGE.msg, .srv, .action: those it defines) import.
importable() {
    local kinds
    kinds=$(cd "$HERE/$1" && { ls -d msg srv action 2>/dev/null || true; } | sed "s/^/$1./" | paste -sd,)
    "$PY" -c "import importlib; [importlib.import_module(m) for m in '$kinds'.split(',')]" 2>/dev/null
}

# Builds interfaces/PACKAGE into VENV unless the stamp, a sourced ROS 2 or /opt/ros/jazzy has it.
build_package() {
    local pkg=$1 stamp=$VENV/.$1 sources build
    sources=$(cd "$HERE/$pkg" && find . -type f | LC_ALL=C sort | xargs sha256sum | sha256sum | cut -c1-64)
    if importable "$pkg"; then
        if [ ! -f "$VENV/share/$pkg/package.xml" ]; then     # not ours: a sourced ROS 2 Jazzy
            echo "$pkg: using the one installed ($("$PY" -c "import $pkg; print($pkg.__path__[0])"))"
            echo external > "$stamp"
            return 0
        fi
        if [ "$(cat "$stamp" 2>/dev/null)" = "$sources" ]; then    # built from these files
            touch "$stamp"                                          # (for make: checked now)
            return 0
        fi
    fi
    if [ -f "/opt/ros/jazzy/share/$pkg/package.xml" ]; then
        echo "$pkg: not built: ROS 2 Jazzy's is in /opt/ros/jazzy (source /opt/ros/jazzy/setup.bash to use it)"
        return 0
    fi
    for tool in cmake c++ cc; do
        command -v $tool >/dev/null ||
            { echo "$pkg: '$tool' not found: apt-get install cmake g++ python3-dev" >&2; return 1; }
    done
    build=$(mktemp -d)
    echo "$pkg: building from $HERE/$pkg into $VENV"
    cmake -S "$HERE/$pkg" -B "$build" -DCMAKE_BUILD_TYPE=Release -DBUILD_TESTING=OFF \
        -DCMAKE_PREFIX_PATH="$PREFIX" -DCMAKE_INSTALL_PREFIX="$PREFIX" -DPython3_EXECUTABLE="$PREFIX/bin/python" \
        > "$build/configure.log" 2>&1 || { cat "$build/configure.log" >&2; rm -rf "$build"; return 1; }
    cmake --build "$build" --parallel "$(nproc)" > "$build/build.log" 2>&1 ||
        { tail -50 "$build/build.log" >&2; rm -rf "$build"; return 1; }
    cmake --install "$build" > "$build/install.log" 2>&1 || { cat "$build/install.log" >&2; rm -rf "$build"; return 1; }
    rm -rf "$build"
    importable "$pkg" || { echo "$pkg: built but not importable from $PY" >&2; return 1; }
    echo "$sources" > "$stamp"
    echo "$pkg: installed into $VENV"
}

for pkg in "${PACKAGES[@]}"; do
    [ -f "$HERE/$pkg/package.xml" ] || { echo "$pkg: no interfaces/$pkg/package.xml" >&2; exit 1; }
    build_package "$pkg"
done
