# Helpers of tests/bench.sh and the scripts it runs (sourced; a measurement, never a test).
. tests/still-demo.sh
. tests/classic-cornell.sh

# median: the median of the numbers on standard input, one a line.
median() { sort -g | awk '{ v[++n] = $1 } END { print (n % 2) ? v[(n + 1) / 2] : (v[n / 2] + v[n / 2 + 1]) / 2 }'; }

# field NAME SIDECAR...: the number NAME ("wall_ms", "cpu_ms", ...) of each timing sidecar.
field() {
    field_name=$1
    shift
    cat "$@" | sed -n "s/.*\"$field_name\": \([0-9.eE+-]*\).*/\1/p"
}

# pass_medians PREFIX SIDECAR...: a line a pass, in the sidecars' order: PREFIX, the pass, the
# median of its gpu_ms over the sidecars, and how many times it ran a frame when more than once.
pass_medians() {
    pass_prefix=$1
    shift
    cat "$@" | tr '{' '\n' |
        sed -n 's/.*"name": "\([^"]*\)", "gpu_ms": \([0-9.eE+-]*\)\(.*\)/\1 \2 \3/p' |
        awk -v prefix="$pass_prefix" '{ if (!($1 in n)) order[++k] = $1; v[$1, ++n[$1]] = $2 + 0
             if (match($0, /"count": [0-9]+/)) count[$1] = substr($0, RSTART + 9, RLENGTH - 9) + 0 }
         END { for (i = 1; i <= k; i++) { p = order[i]; c = n[p];
               for (a = 2; a <= c; a++) { x = v[p, a]; b = a - 1;
                   while (b >= 1 && v[p, b] > x) { v[p, b + 1] = v[p, b]; b-- } v[p, b + 1] = x }
               m = (c % 2) ? v[p, (c + 1) / 2] : (v[p, c / 2] + v[p, c / 2 + 1]) / 2;
               printf "%spass %-10s median %8.3f ms gpu%s\n", prefix, p, m,
                   (count[p] > 1 ? sprintf(" (%d a frame)", count[p]) : "") } }'
}

# render JOB DIR OPTION...: raybundle render on the bench's device into DIR.
render() {
    render_job=$1 render_dir=$2
    shift 2
    [ -z "${RB_BENCH_DEVICE:-}" ] || set -- "$@" --device "$RB_BENCH_DEVICE"
    "$BUILD/raybundle" render "$render_job" --out "$render_dir" -q "$@" </dev/null >/dev/null
}

# relmse TEST TRUTH [LAYER]: the relative MSE of the image TEST against TRUTH.
relmse() {
    "$BUILD/raybundle" compare "$1" "$2" --layer "${3:-beauty}" </dev/null |
        sed -n 's/^relmse *//p'
}
