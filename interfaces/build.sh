#!/usr/bin/env bash
# Build the message packages under interfaces/ (tf2_msgs: TFMessage) into the venv VENV.
#
#   interfaces/build.sh VENV        (PYTHON=python3 creates VENV if it does not exist)
#
# The PyPI ROS 2 Jazzy wheels have no tf2_msgs; this generates it from interfaces/tf2_msgs
# with the PyPI rosidl tooling (requirements-build.txt), cmake and a C/C++ compiler, and
# installs it into VENV, which the ROS wheels already use as their prefix (python package in
# site-packages, libraries in lib/, ament index and CMake config in share/). The installed
# package is the cache: VENV/.tf2_msgs holds the hash of the definitions it was built from,
# and a run with the same definitions builds nothing. Where another tf2_msgs is importable
# (a sourced ROS 2 Jazzy) or /opt/ros/jazzy has one, it builds nothing either.
set -euo pipefail
VENV=${1:?usage: interfaces/build.sh VENV}
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
STAMP=$VENV/.tf2_msgs
PY=$VENV/bin/python

if [ ! -x "$PY" ]; then
    "${PYTHON:-python3}" -m venv "$VENV" || { echo "python3 -m venv failed: apt-get install python3-venv" >&2; exit 1; }
fi
LOCK=$HERE/../requirements-lock.txt                 # the versions the suite passed with
"$PY" -m pip install --quiet -r "$HERE/../requirements-build.txt" $([ -f "$LOCK" ] && echo -c "$LOCK")
SOURCES=$(cd "$HERE/tf2_msgs" && find . -type f | LC_ALL=C sort | xargs sha256sum | sha256sum | cut -c1-64)
if "$PY" -c 'import tf2_msgs.msg' 2>/dev/null; then
    if [ ! -f "$VENV/share/tf2_msgs/package.xml" ]; then     # not ours: a sourced ROS 2 Jazzy
        echo "tf2_msgs: using the one installed ($("$PY" -c 'import tf2_msgs; print(tf2_msgs.__path__[0])'))"
        echo external > "$STAMP"
        exit 0
    fi
    [ "$(cat "$STAMP" 2>/dev/null)" = "$SOURCES" ] && exit 0   # built from these definitions
fi
if [ -f /opt/ros/jazzy/share/tf2_msgs/package.xml ]; then
    echo "tf2_msgs: not built: ROS 2 Jazzy's is in /opt/ros/jazzy (source /opt/ros/jazzy/setup.bash to use it)"
    exit 0
fi
for tool in cmake c++ cc; do
    command -v $tool >/dev/null ||
        { echo "tf2_msgs: '$tool' not found: apt-get install cmake g++ python3-dev" >&2; exit 1; }
done

BUILD=$(mktemp -d)
trap 'rm -rf "$BUILD"' EXIT
echo "tf2_msgs: building from $HERE/tf2_msgs into $VENV"
PREFIX=$(cd "$VENV" && pwd)
cmake -S "$HERE/tf2_msgs" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release -DBUILD_TESTING=OFF \
    -DCMAKE_PREFIX_PATH="$PREFIX" -DCMAKE_INSTALL_PREFIX="$PREFIX" -DPython3_EXECUTABLE="$PREFIX/bin/python" \
    > "$BUILD/configure.log" 2>&1 || { cat "$BUILD/configure.log" >&2; exit 1; }
cmake --build "$BUILD" --parallel "$(nproc)" > "$BUILD/build.log" 2>&1 || { tail -50 "$BUILD/build.log" >&2; exit 1; }
cmake --install "$BUILD" > "$BUILD/install.log" 2>&1 || { cat "$BUILD/install.log" >&2; exit 1; }
"$PY" -c 'import tf2_msgs.msg' || { echo "tf2_msgs: built but not importable from $PY" >&2; exit 1; }
echo "$SOURCES" > "$STAMP"
echo "tf2_msgs: installed into $VENV"
