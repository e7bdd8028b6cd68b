#!/usr/bin/env bash
# Compile time of the planar n-link flexible-joint arm with two Hirschorn steps per joint,
# release, warm dependencies, for two crates per n (see docs/arms.md):
#   model  examples/arm_compile/modelN.rs: the model crate, the declaration alone compiled as a
#          library (every routine the macro generates for the arm is compiled);
#   use    examples/arm_compile/armN.rs: a crate that declares the arm and uses it as
#          benches/arms.rs does (design, one DPC update, a closed loop), so it also compiles
#          DPC's generic code instantiated for the arm.
# Each is built once (so that every dependency is compiled), then touched, and the rebuild,
# which compiles that crate alone, is timed. Prints the load average first, then the
# wall-clock and CPU times.
# Usage: bench/arm_compile_time.sh [N ...] (default: 8 16). With DPC_PART_OPERATIONS=0 in the
# environment the macro emits every routine in one piece (docs/arms.md compares the two).
set -euo pipefail
cd "$(dirname "$0")/.."
uptime
for n in "${@:-8 16}"; do
  for each in $n; do
    for crate in model use; do
      if [ "$crate" = model ]; then
        example="arm_model_$each" file="examples/arm_compile/model$each.rs"
      else
        example="arm_compile_$each" file="examples/arm_compile/arm$each.rs"
      fi
      cargo build --release --quiet --features arm-compile-time --example "$example"
      touch "$file"
      # Wall-clock time, and the CPU time, which depends less on other work on the machine.
      TIMEFORMAT="n = $each, $crate: %R s wall, %U s user + %S s system CPU"
      time cargo build --release --quiet --features arm-compile-time --example "$example"
    done
  done
done
