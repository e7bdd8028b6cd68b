#!/usr/bin/env bash
# Peer comparison: dpc-core's BDF against the BDF of the Rust crate diffsol (version 0.19, dense
# nalgebra LU, mass-matrix form) on the Test Set's transistor amplifier and Robertson, same
# equations, tolerances and end times.
#
#   bash bench/diffsol_peer.sh
#
# bench/diffsol_peer is a workspace of its own, so neither the project's builds nor CI compile
# diffsol; this script builds it in release mode and prints the table of docs/integrators.md.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
cd "$here/diffsol_peer"
cargo run --release --quiet
