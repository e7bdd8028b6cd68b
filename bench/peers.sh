#!/usr/bin/env bash
# The peer work-precision table: dpc-core (Radau IIA and the BDF), SUNDIALS IDA 6.4.1 and the
# BDF of the Rust crate diffsol 0.19 on the same problems, equations, initial values,
# tolerances and end points, side by side (docs/integrators.md, README "Integrators").
#
#   bash bench/peers.sh                  # all three codes
#   bash bench/peers.sh dpc ida          # a subset: any of dpc, ida, diffsol
#
# Installs libsundials-dev with apt-get when missing (needs root) and compiles
# bench/ida_peer.c with -O2; runs dpc-core's example work_precision and bench/diffsol_peer (a
# workspace of its own, so that neither the project's builds nor CI compile diffsol) in release
# mode. Each prints rows behind a sort key; the rows are merged by problem, tolerance and code.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
codes=("$@")
[ ${#codes[@]} -eq 0 ] && codes=(dpc ida diffsol)
rows="$(mktemp)"
trap 'rm -f "$rows"' EXIT
for code in "${codes[@]}"; do
    case "$code" in
    dpc)
        (cd "$here/.." && cargo run --release --quiet -p dpc-core --example work_precision) >>"$rows"
        ;;
    ida)
        if [ ! -e /usr/include/ida/ida.h ]; then
            apt-get update
            DEBIAN_FRONTEND=noninteractive apt-get install -y libsundials-dev
        fi
        out="${TMPDIR:-/tmp}/ida_peer"
        cc -O2 -o "$out" "$here/ida_peer.c" -lsundials_ida -lsundials_nvecserial \
            -lsundials_sunmatrixdense -lsundials_sunlinsoldense \
            -lsundials_sunmatrixband -lsundials_sunlinsolband -lm
        "$out" >>"$rows"
        ;;
    diffsol)
        (cd "$here/diffsol_peer" && cargo run --release --quiet) >>"$rows"
        ;;
    *)
        echo "unknown code '$code' (dpc, ida or diffsol)" >&2
        exit 2
        ;;
    esac
done
echo "| problem | rtol | code | steps | error-test failures | Newton failures | Jacobians | scd | time [ms] |"
echo "|---|---|---|---|---|---|---|---|---|"
sort -s -t $'\t' -k1,1 "$rows" | cut -f2-
# dpc's time as a fraction of the peers' and the digits it gains, per problem and tolerance
# (from the rows above; "fails" where that code failed, empty where it was not run).
echo
echo "| problem | rtol | dpc BDF / IDA | dpc Radau / IDA | dpc BDF / diffsol | scd dpc BDF - IDA |"
echo "|---|---|---|---|---|---|"
sort -s -t $'\t' -k1,1 "$rows" | cut -f2- | awk -F'|' '
    function trim(s) { gsub(/^ +| +$/, "", s); return s }
    function code(c) {
        if (c == "dpc BDF") return "bdf"
        if (c == "dpc Radau") return "radau"
        if (c ~ /^IDA/) return "ida"
        if (c ~ /^diffsol/ && c !~ /given/) return "diffsol"
        return ""
    }
    function ratio(a, b) {
        if (!((key, a) in ms) || !((key, b) in ms)) return ""
        if (ms[key, a] == "" ) return "fails"
        if (ms[key, b] == "") return (b == "ida" ? "IDA" : b) " fails"
        return sprintf("%.2f", ms[key, a] / ms[key, b])
    }
    {
        k = trim($2) " | " trim($3); c = code(trim($4))
        if (c == "") next
        if (!(k in seen)) { seen[k] = 1; order[++n] = k }
        ms[k, c] = trim($10); scd[k, c] = trim($9)
    }
    END {
        for (i = 1; i <= n; i++) {
            key = order[i]
            d = ""
            if (scd[key, "bdf"] != "" && scd[key, "ida"] != "")
                d = sprintf("%+.2f", scd[key, "bdf"] - scd[key, "ida"])
            printf "| %s | %s | %s | %s | %s |\n", key, ratio("bdf", "ida"), ratio("radau", "ida"), ratio("bdf", "diffsol"), d
        }
    }'
