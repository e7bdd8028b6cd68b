#!/usr/bin/env bash
# Compile time of a crate using the planar n-link flexible-joint arm with two Hirschorn steps
# per joint (examples/arm_compile/armN.rs), release, warm dependencies: builds the example
# once (so that every dependency is compiled), then touches it and times the rebuild, which
# compiles the example alone. Prints the wall-clock and CPU times; the load average first.
# Usage: bench/arm_compile_time.sh [N ...] (default: 8 16). With DPC_PART_OPERATIONS=0 in the
# environment the macro emits every routine in one piece (docs/arms.md compares the two).
set -euo pipefail
cd "$(dirname "$0")/.."
uptime
for n in "${@:-8 16}"; do
  for each in $n; do
    cargo build --release --quiet --features arm-compile-time --example "arm_compile_$each"
    touch "examples/arm_compile/arm$each.rs"
    # Wall-clock time, and the CPU time, which depends less on other work on the machine.
    TIMEFORMAT="n = $each: %R s wall, %U s user + %S s system CPU"
    time cargo build --release --quiet --features arm-compile-time --example "arm_compile_$each"
  done
done
