#!/usr/bin/env bash
# SUNDIALS IDA 6.4.1 (Debian package libsundials-dev) beside dpc-core on the same problems:
# the peer table of bench/peers.sh without diffsol.
#
#   bash bench/ida_peer.sh
set -euo pipefail
exec bash "$(cd "$(dirname "$0")" && pwd)/peers.sh" dpc ida
