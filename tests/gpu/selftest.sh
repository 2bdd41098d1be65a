#!/bin/bash
# tests/gpu/selftest.sh [--tarball PATH]: the GPU check end to end on lavapipe, in quick mode (make
# check-dist runs it once the tarball exists). Builds a kit into a temporary folder with
# tests/gpu/kit.sh, runs tests/gpu/gpu-check.sh --quick --device llvmpipe (with the kit's Vulkan
# loader, so that path is exercised too), and checks that every step passed and every table
# is filled; then stops a second check midway and checks what it leaves. Prints ok / FAIL lines;
# exit status 1 when one failed. The tarball: --tarball, else the newest
# dist/raybundle-*-linux-x86_64.tar.xz (as kit.sh finds it).
set -u
here=$(cd "$(dirname "$0")" && pwd)
repo=$(cd "$here/../.." && pwd)
cd "$repo" || exit 2
tarball_opt=()
if [ $# -ge 2 ] && [ "$1" = --tarball ]; then
    tarball_opt=(--tarball "$2")
elif [ $# -gt 0 ]; then
    echo "usage: tests/gpu/selftest.sh [--tarball PATH]" >&2
    exit 2
fi
T=$(mktemp -d "${TMPDIR:-/tmp}/gpu-selftest.XXXXXX") || exit 2
trap 'rm -rf "$T"' EXIT
failed=0

ok() { echo "ok   $1"; }
fail() {
    echo "FAIL $1"
    [ $# -lt 2 ] || echo "$2" | sed 's/^/     /'
    failed=$((failed + 1))
}
# check NAME COMMAND...: ok when COMMAND succeeds.
check() {
    local name=$1
    shift
    if "$@" >"$T/check.out" 2>&1; then ok "$name"; else fail "$name" "$(tail -n 20 "$T/check.out")"; fi
}

start=$(date +%s)
if tests/gpu/kit.sh "$T/kit" "${tarball_opt[@]}" >"$T/kit.log" 2>&1; then
    ok "kit.sh builds a kit ($(grep 'total' "$T/kit.log" | sed 's/^ *//'))"
else
    fail "kit.sh builds a kit" "$(tail -n 20 "$T/kit.log")"
    echo "selftest: $failed failed"
    exit 1
fi
for f in kit.json layer/libVkLayer_khronos_validation.so.xz layer/VkLayer_khronos_validation.json \
    vulkan/libvulkan.so.1 jobs/demo.yaml jobs/cornell.yaml scenes/cornell-box/CornellBox.glb \
    scenes/demo/room.gltf lavapipe/demo-bdpt/frame.0002.exr lavapipe/cornell-hybrid/frame.0002.exr \
    jobs/blend.yaml scenes/blend/blend.gltf scenes/blend/alpha.png lavapipe/blend-direct/frame.0002.exr; do
    check "the kit holds $f" test -s "$T/kit/$f"
done

t0=$(date +%s)
tests/gpu/gpu-check.sh "$T/out" --kit "$T/kit" --quick --device llvmpipe --kit-loader \
    --scratch "$T/scratch" >"$T/check.log" 2>&1
status=$?
took=$(($(date +%s) - t0))
if [ "$status" = 0 ]; then
    ok "gpu-check.sh --quick passes on lavapipe in $took s"
else
    fail "gpu-check.sh --quick passes on lavapipe (exit $status, $took s)" "$(grep -E ': (fail|skipped)' "$T/check.log" | head -n 20)"
fi
for f in gpu-check.json gpu-check.md gpu-check.log; do
    check "OUTDIR holds $f" test -s "$T/out/$f"
done
check "OUTDIR holds those three files alone" test "$(ls "$T/out" | wc -l)" = 3
check "the scratch folder is removed" test ! -e "$T/scratch"

# The record: every step passed, each with its command and time, and the figures are there.
python3 - "$T/out/gpu-check.json" >"$T/json.check" 2>&1 <<'EOF'
import json, sys
d = json.load(open(sys.argv[1]))
problems = []
def need(cond, what):
    if not cond:
        problems.append(what)
need(d["state"] == "done", "state is %s, not done" % d["state"])
need(d["mode"] == "quick", "mode is %s" % d["mode"])
steps = {s["id"]: s for s in d["steps"]}
for s in d["steps"]:
    need(s["status"] == "pass", "%s: %s %s" % (s["id"], s["status"], s.get("note", "")))
    need(isinstance(s.get("wall_s"), (int, float)), "%s has no wall time" % s["id"])
    need(bool(s.get("cmd")), "%s has no command" % s["id"])
need(d["summary"].get("pass") == len(d["steps"]), "summary %s" % d["summary"])
need("llvmpipe" in d["device"].get("name", ""), "device %s" % d["device"])
need(d["host"].get("loader", "").startswith("kit:"), "loader %s" % d["host"].get("loader"))
need("libvulkan.so.1" in d["host"].get("loader", ""), "loader %s" % d["host"].get("loader"))
need(d["host"].get("glibc"), "no glibc version")
need(d["host"].get("uname"), "no uname")
need("validation layer: available" in d["raybundle"].get("info", ""), "info: no validation layer")
for sc in ("demo", "cornell", "blend"):
    for ig in ("direct", "bdpt", "hybrid", "reference"):
        f = steps.get("validate/%s/%s" % (sc, ig), {}).get("figures", {})
        need(f.get("frames") == 2 and f.get("nonfinite") == 0 and f.get("wall_ms_median", 0) > 0,
             "validate/%s/%s figures %s" % (sc, ig, f))
    for ig in ("direct", "bdpt", "hybrid"):
        f = steps.get("compare/%s/%s" % (sc, ig), {}).get("figures", {})
        # The same job on the same driver: the kit's lavapipe frame to the bit.
        need(f.get("relmse") == 0 and f.get("rmse") == 0 and f.get("pixels") == 640 * 360,
             "compare/%s/%s against the kit's frame of the same driver: %s" % (sc, ig, f))
        need(f.get("job_hash") and f.get("job_hash") == f.get("lavapipe_job_hash"),
             "compare/%s/%s job hashes %s" % (sc, ig, f))
for ig in ("direct", "bdpt", "hybrid"):
    for what in ("twice", "chunks"):
        f = steps.get("determinism/%s/%s" % (ig, what), {}).get("figures", {})
        need(f.get("files", 0) >= 2 and f.get("compared") == f.get("files") and not f.get("differ"),
             "determinism/%s/%s %s" % (ig, what, f))
for size in d["settings"]["bench"]["sizes"]:
    for ig in ("direct", "bdpt", "hybrid"):
        f = steps.get("bench/%s/%s" % (size, ig), {}).get("figures", {})
        p = f.get("passes_ms", {})
        need(f.get("runs") == 2 and f.get("size") == size, "bench/%s/%s runs %s size %s"
             % (size, ig, f.get("runs"), f.get("size")))
        need(len(p) >= 5 and all(v > 0 for v in p.values()) and f.get("gpu_total_ms", 0) > 0,
             "bench/%s/%s per-pass figures %s" % (size, ig, p))
        need({"gbuffer", "shadow", "direct", "output"} <= set(p), "bench/%s/%s passes %s" % (size, ig, sorted(p)))
for p in problems:
    print(p)
sys.exit(1 if problems else 0)
EOF
if [ $? = 0 ]; then ok "gpu-check.json: every step passed, with its command, time and figures"; else
    fail "gpu-check.json: every step passed, with its command, time and figures" "$(head -n 30 "$T/json.check")"
fi

# The Markdown: every table filled, no failure, no empty cell where a figure belongs.
md="$T/out/gpu-check.md"
check "gpu-check.md says done with 0 failed" grep -q 'State: \*\*done\*\*.* 0 failed, 0 skipped' "$md"
for h in '## Validation' '## Against lavapipe' '## Determinism' '## GPU time per pass' '### 320x180' '### 640x360'; do
    check "gpu-check.md has '$h'" grep -qF "$h" "$md"
done
check "gpu-check.md: 12 validation cells passed (demo, Cornell box, blended scene)" \
    test "$(grep -E '^\| (demo|cornell|blend) \| pass, ' "$md" | grep -o 'pass, ' | wc -l)" = 12
check "gpu-check.md: 9 comparisons, relMSE 0 against the same driver" \
    test "$(grep -cE '^\| (demo|cornell|blend) \| (direct|bdpt|hybrid) \| 0 \| 0 \| 0 \| inf \|.*\| pass \|$' "$md")" = 9
check "gpu-check.md: 3 integrators with the same bits twice and in chunks" \
    test "$(grep -cE '^\| (direct|bdpt|hybrid) \| same bits \| same bits \| [0-9]+ \|$' "$md")" = 3
check "gpu-check.md: a GPU total for each integrator at both sizes" \
    test "$(grep -cE '^\| \*\*GPU total\*\* \| [0-9.e+-]+ \| [0-9.e+-]+ \| [0-9.e+-]+ \|$' "$md")" = 2
check "gpu-check.md: the bdpt/direct and hybrid/direct ratios at both sizes" \
    test "$(grep -cE '^\| GPU total / direct \| 1\.00 \| [0-9.]+ \| [0-9.]+ \|$' "$md")" = 2
check "gpu-check.md has no failure section" sh -c "! grep -q '^## Failures' '$md'"
check "gpu-check.log logs every step's command and time" \
    test "$(grep -c '^\[ *[0-9.]*s\] == ' "$T/out/gpu-check.log")" -ge 50

# Stopped midway (as a scheduler or a time limit would): a JSON file that parses, saying so, the
# steps done so far recorded, and a Markdown file.
tests/gpu/gpu-check.sh "$T/stop" --kit "$T/kit" --quick --device llvmpipe >"$T/stop.log" 2>&1 &
pid=$!
i=0
while ! grep -q '"id": "validate/demo/bdpt"' "$T/stop/gpu-check.json" 2>/dev/null && [ $i -lt 600 ]; do
    sleep 0.1
    i=$((i + 1))
done
kill -TERM "$pid"
wait "$pid"
status=$?
check "a check stopped by SIGTERM exits non-zero" test "$status" -ne 0
check "it leaves a JSON file that says interrupted, with the steps done" python3 -c "
import json, sys
d = json.load(open('$T/stop/gpu-check.json'))
assert d['state'] == 'interrupted', d['state']
assert d['summary']['pass'] >= 6, d['summary']
"
check "and a Markdown file that says so" grep -q 'State: \*\*interrupted\*\*' "$T/stop/gpu-check.md"
check "and its log" grep -q 'interrupted during' "$T/stop/gpu-check.log"

echo "selftest: $failed failed, $(($(date +%s) - start)) s"
[ "$failed" = 0 ]
