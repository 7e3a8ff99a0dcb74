# Shared steps of the peers' build scripts (scripts/external/<system>): sourced, not run.
# Each script builds a system from a source folder the user names, into a workspace of its
# own (the source folder is never written to), applying only the build fixes a current Debian
# 12 needs, each as a command in that script.

DRIFTLAB_ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)

# die MESSAGE: the script's name, the message, exit 2.
die() {
  echo "$(basename "$0"): $*" >&2
  exit 2
}

# peer_source SOURCE MARKER URL: SOURCE as an absolute path, after checking that it holds
# MARKER (a file every checkout of the system has).
peer_source() {
  local src=$1 marker=$2 url=$3
  [ -n "$src" ] || die "usage: $(basename "$0") SOURCE [WORKSPACE]; SOURCE is a checkout of $url"
  [ -f "$src/$marker" ] || die "$src/$marker: not found; expected a checkout of $url"
  (cd "$src" && pwd)
}

# peer_packages PACKAGE...: installs the Debian packages that are missing (as root, or sudo).
peer_packages() {
  "$DRIFTLAB_ROOT/scripts/setup-deps" --only rsync "$@"
}

# peer_copy SOURCE DEST FIX: copies SOURCE to DEST with the function FIX applied to the copy
# (run in the copy's folder). Files whose content did not change keep their times, so a second
# build rebuilds only what changed; a changed one is written now (not with its source's time,
# which can be older than its object file).
peer_copy() {
  local src=$1 dest=$2 fix=$3 stage
  mkdir -p "$(dirname "$dest")"
  stage=$(mktemp -d "${dest%/}.stage.XXXXXX")
  cp -a "$src/." "$stage/"
  (cd "$stage" && "$fix")
  mkdir -p "$dest"
  rsync --recursive --links --perms --checksum --delete "$stage/" "$dest/"
  rm -rf "$stage"
}

# peer_catkin_make WORKSPACE CMAKE_ARGUMENT...: builds the catkin workspace in Release with
# Debian's catkin, against Debian's Python 3 (its ROS modules live there, whatever python3 the
# PATH finds first).
peer_catkin_make() {
  local ws=$1
  shift
  (cd "$ws" && catkin_make -DCMAKE_BUILD_TYPE=Release -DPYTHON_EXECUTABLE=/usr/bin/python3 \
    -DPython3_EXECUTABLE=/usr/bin/python3 "$@" \
    -j"${JOBS:-$(nproc)}")
}
