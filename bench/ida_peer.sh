#!/usr/bin/env bash
# Peer comparison: SUNDIALS IDA from the Debian package libsundials-dev against dpc-core's BDF
# on Robertson (index 1), the Cartesian pendulum (index 3) and the Test Set transistor amplifier
# (index 1, singular mass matrix), same tolerances.
#
#   bash bench/ida_peer.sh
#
# Installs libsundials-dev with apt-get when missing (needs root), compiles bench/ida_peer.c
# with -O2, prints IDA's work-precision table, then runs dpc-core's table in release mode.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
if [ ! -e /usr/include/ida/ida.h ]; then
    apt-get update
    DEBIAN_FRONTEND=noninteractive apt-get install -y libsundials-dev
fi
out="${TMPDIR:-/tmp}/ida_peer"
cc -O2 -o "$out" "$here/ida_peer.c" \
    -lsundials_ida -lsundials_nvecserial -lsundials_sunmatrixdense -lsundials_sunlinsoldense -lm
echo "## SUNDIALS IDA $(dpkg-query -W -f='${Version}' libsundials-dev 2>/dev/null || echo '?')"
"$out"
echo
echo "## dpc-core BDF"
cd "$here/.."
cargo run --release -p dpc-core --example work_precision 2>/dev/null \
    | grep '^|'
