#!/usr/bin/env bash
# The BDF of the Rust crate diffsol 0.19 beside dpc-core on the same problems: the peer table of
# bench/peers.sh without IDA.
#
#   bash bench/diffsol_peer.sh
set -euo pipefail
exec bash "$(cd "$(dirname "$0")" && pwd)/peers.sh" dpc diffsol
