#!/usr/bin/env bash
# Peer comparison: dpc's generated wheel code against CasADi's generated C, in one benchmark
# binary (benches/casadi_peer.rs), on the same random points, interleaved.
#
#   bash bench/casadi/run.sh
#
# Installs CasADi with pip into a virtual environment under the cargo target directory (or
# $TMPDIR when CARGO_TARGET_DIR is unset), writes its C for the wheel (bench/casadi/wheel.py,
# the equations of models/src/wheel.rs) to bench/casadi/generated/, then runs the benchmark
# with the feature `casadi-peer`, whose build script compiles that C with -O2 (cc crate).
# Extra arguments go to the benchmark (e.g. `--bench` filters of criterion).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
venv="${CARGO_TARGET_DIR:-${TMPDIR:-/tmp}}/casadi-venv"
if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv"
fi
"$venv/bin/python" -c 'import casadi' 2>/dev/null || "$venv/bin/pip" install --quiet casadi
"$venv/bin/python" "$here/wheel.py" "$here/generated"
cd "$root"
cargo bench -p dpc --features casadi-peer --bench casadi_peer -- "$@"
