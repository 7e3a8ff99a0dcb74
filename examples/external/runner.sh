# Shared steps of the peers' runners here (sourced, not run).

# peer_built FILE SYSTEM SCRIPT: FILE, a file of a peer's build, must exist; else an error naming
# the script that builds SYSTEM.
peer_built() {
  [ -e "$1" ] || {
    echo "$(basename "$0"): $1: not found; build $2 with scripts/external/$3" >&2
    exit 2
  }
}

# with_imu MODE INERTIAL VISUAL: 1 when MODE is INERTIAL, 0 when it is VISUAL, else an error.
with_imu() {
  case "$1" in
    "$2") echo 1 ;;
    "$3") echo 0 ;;
    *) echo "$(basename "$0"): mode '$1': expected $2 or $3" >&2; return 2 ;;
  esac
}
