#!/usr/bin/env python3
"""The record of tests/gpu/gpu-check.sh: OUTDIR/gpu-check.json and OUTDIR/gpu-check.md.

Every change rewrites both files whole, under a temporary name and renamed, so that a check
killed at any moment leaves a JSON file that parses and a Markdown table of what was done so far.
Standard library only: this runs on the GPU machine too, where nothing of ours is installed.

    report.py init OUT MODE BUDGET_S SETTINGS_JSON
    report.py set OUT KEY VALUE            KEY a dotted path; VALUE a string
    report.py set-json OUT KEY JSON        the same, VALUE as JSON
    report.py set-file OUT KEY FILE        the same, VALUE the file's text (trailing newline cut)
    report.py start OUT ID GROUP CMD       a step begins (status running)
    report.py end OUT ID STATUS RC WALL_S [--stderr FILE] [--note TEXT] [--figures FILE]
    report.py skip OUT ID GROUP REASON
    report.py finish OUT STATE             done or interrupted
    report.py render-figures DIR FRAMES DEVICE   figures of a render into DIR (a JSON object on
                                           stdout); exit 1, with the reason on stderr, when a
                                           frame is missing or unclean or the device is not DEVICE
    report.py bench-figures DIR DEVICE     per-pass medians of a raybundle bench set
    report.py compare-figures COMPARE_JSON GPU_SIDECAR LAVAPIPE_SIDECAR
    report.py samebits BASE OTHER...       every frame*.exr of BASE against the same file in
                                           each OTHER (folders whose files are pooled), byte by byte
    report.py get OUT KEY                  print a value of OUT/gpu-check.json
    report.py jget FILE KEY                print a value of any JSON file (kit.json)
    report.py pick INFO_FILE [SELECTOR]    the device `raybundle info` listed that render
                                           --device SELECTOR would take (an index, or part of
                                           the name, case-insensitive), or without SELECTOR the
                                           first whose type is not CPU: a JSON object; exit 1
                                           when there is none
    report.py md OUT                       rewrite the Markdown from the JSON
"""

import datetime
import json
import os
import re
import statistics
import sys
import time

JSON_NAME = "gpu-check.json"
MD_NAME = "gpu-check.md"
TAIL_LINES = 15
# Across drivers the bits differ, but a frame of the same job is the same picture: a relMSE
# above this against lavapipe's frame fails the comparison (measured against the kit's frames:
# the demo's frame upside down is 6 to 18, black 0.4 to 0.5, 20% too dark 0.02). A sanity
# bound, not a quality target.
SANITY_RELMSE = 0.1


def now():
    return datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")


def load(out):
    with open(os.path.join(out, JSON_NAME), encoding="utf-8") as f:
        return json.load(f)


def write_atomic(path, text):
    tmp = path + ".tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(text)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


def save(out, doc):
    doc["updated_utc"] = now()
    if doc.get("state") == "running":
        doc["elapsed_s"] = round(time.time() - doc.get("started_epoch", time.time()), 1)
    counts = {"pass": 0, "fail": 0, "skip": 0, "running": 0}
    for s in doc["steps"]:
        counts[s["status"]] = counts.get(s["status"], 0) + 1
    doc["summary"] = counts
    doc["tables"] = tables(doc)
    write_atomic(os.path.join(out, JSON_NAME), json.dumps(doc, indent=1, sort_keys=False) + "\n")
    write_atomic(os.path.join(out, MD_NAME), markdown(doc))


def set_path(doc, key, value):
    parts = key.split(".")
    d = doc
    for p in parts[:-1]:
        d = d.setdefault(p, {})
    d[parts[-1]] = value


def get_path(doc, key):
    d = doc
    for p in key.split("."):
        if isinstance(d, list):
            d = d[int(p)]
        else:
            d = d[p]
    return d


def find_step(doc, sid):
    for s in doc["steps"]:
        if s["id"] == sid:
            return s
    return None


def tail(path, n=TAIL_LINES):
    try:
        with open(path, encoding="utf-8", errors="replace") as f:
            lines = f.read().splitlines()
    except OSError:
        return []
    lines = [ln for ln in lines if ln.strip()]
    return [ln[:400] for ln in lines[-n:]]


# ---- figures ------------------------------------------------------------------------------


def read_json(path):
    with open(path, encoding="utf-8") as f:
        return json.load(f)


def parse_frames(spec):
    """A-B or A: the frame numbers."""
    if "-" in spec:
        a, b = spec.split("-", 1)
        return list(range(int(a), int(b) + 1))
    return [int(spec)]


def render_figures(d, frames, device):
    problems = []
    sidecars = []
    for f in parse_frames(frames):
        exr = os.path.join(d, "frame.%04d.exr" % f)
        side = os.path.join(d, "frame.%04d.timing.json" % f)
        if not os.path.isfile(exr):
            problems.append("frame %d: no EXR" % f)
        if not os.path.isfile(side):
            problems.append("frame %d: no timing sidecar" % f)
            continue
        try:
            sidecars.append(read_json(side))
        except (OSError, ValueError) as e:
            problems.append("frame %d: unreadable sidecar (%s)" % (f, e))
    fig = {"frames": len(sidecars)}
    if sidecars:
        fig["wall_ms_median"] = statistics.median(s.get("wall_ms", 0) for s in sidecars)
        fig["gpu_total_ms_median"] = statistics.median(s.get("gpu_total_ms", 0) for s in sidecars)
        fig["nonfinite"] = sum(int(s.get("nonfinite", 0)) for s in sidecars)
        fig["device"] = sidecars[0].get("device")
        fig["driver"] = sidecars[0].get("driver")
        fig["job_hash"] = sidecars[0].get("job_hash")
        bn = [s["bundle_nodes"] for s in sidecars if "bundle_nodes" in s]
        if bn:
            fig["bundle_nodes_max"] = max(b.get("max", 0) for b in bn)
            fig["overflow"] = any(b.get("overflow") for b in bn)
        if "spp" in sidecars[0]:
            fig["spp"] = sidecars[0]["spp"]
        if fig["nonfinite"]:
            problems.append("%d NaN or infinite values" % fig["nonfinite"])
        if device and fig["device"] != device:
            problems.append("rendered on '%s', not on '%s'" % (fig["device"], device))
    return fig, problems


def merge_order(orders):
    """One pass order from several integrators' orders: a pass new to the list goes right
    after the pass that precedes it in its own integrator's order."""
    merged = []
    for order in orders:
        prev = None
        for p in order:
            if p not in merged:
                at = merged.index(prev) + 1 if prev is not None else 0
                # Keep passes already placed after prev that this order has not reached yet.
                while at < len(merged) and merged[at] not in order:
                    at += 1
                merged.insert(at, p)
            prev = p
    return merged


def bench_figures(d, device):
    problems = []
    try:
        bench = read_json(os.path.join(d, "bench.json"))
    except (OSError, ValueError) as e:
        return {}, ["no readable bench.json (%s)" % e]
    runs = sorted(r for r in os.listdir(d) if r.startswith("run-"))
    per_pass = {}
    order = []
    totals, walls = [], []
    overflow = False
    nonfinite = 0
    frames = None
    for r in runs:
        files = sorted(f for f in os.listdir(os.path.join(d, r)) if f.endswith(".timing.json"))
        if not files:
            problems.append("%s holds no timing sidecar" % r)
            continue
        frames = len(files)
        sums, counts = {}, {}
        tot, wall = [], []
        for fn in files:
            s = read_json(os.path.join(d, r, fn))
            for p in s.get("passes", []):
                name = p["name"]
                if name not in order:
                    order.append(name)
                sums[name] = sums.get(name, 0.0) + float(p.get("gpu_ms", 0))
                counts[name] = p.get("count", 1)
            tot.append(float(s.get("gpu_total_ms", 0)))
            wall.append(float(s.get("wall_ms", 0)))
            overflow = overflow or bool(s.get("bundle_nodes", {}).get("overflow"))
            nonfinite += int(s.get("nonfinite", 0))
        for name, v in sums.items():
            per_pass.setdefault(name, {"runs": [], "count": counts[name]})["runs"].append(
                v / len(files))
        totals.append(sum(tot) / len(tot))
        walls.append(sum(wall) / len(wall))
    fig = {
        "device": bench.get("device"),
        "driver": bench.get("driver"),
        "integrator": bench.get("integrator"),
        "size": "%sx%s" % (bench.get("width"), bench.get("height")),
        "runs": len(totals),
        "frames_per_run": frames,
        "frames": bench.get("frames"),
        "pass_order": order,
        "passes_ms": {k: statistics.median(v["runs"]) for k, v in per_pass.items()},
        "pass_counts": {k: v["count"] for k, v in per_pass.items()},
        "gpu_total_ms": statistics.median(totals) if totals else None,
        "wall_ms": statistics.median(walls) if walls else None,
        "overflow": overflow,
        "nonfinite": nonfinite,
    }
    if not totals:
        problems.append("no run has timings")
    if device and fig["device"] != device:
        problems.append("measured on '%s', not on '%s'" % (fig["device"], device))
    if nonfinite:
        problems.append("%d NaN or infinite values" % nonfinite)
    return fig, problems


def compare_figures(cmp_json, gpu_side, lava_side):
    problems = []
    c = read_json(cmp_json)
    fig = {k: c.get(k) for k in ("pixels", "relmse", "rmse", "mae", "psnr", "peak", "max_error",
                                  "max_error_pixel", "nonfinite_pixels", "layer")}
    g = read_json(gpu_side)
    lv = read_json(lava_side)
    fig["job_hash"] = g.get("job_hash")
    fig["lavapipe_job_hash"] = lv.get("job_hash")
    fig["device"] = g.get("device")
    fig["lavapipe_device"] = lv.get("device")
    if fig["job_hash"] != fig["lavapipe_job_hash"]:
        problems.append("not the same job: job hash %s here, %s in the kit's frame"
                        % (fig["job_hash"], fig["lavapipe_job_hash"]))
    if c.get("nonfinite_pixels"):
        problems.append("%s NaN or infinite pixels" % c.get("nonfinite_pixels"))
    if not isinstance(c.get("relmse"), (int, float)) or c["relmse"] > SANITY_RELMSE:
        problems.append("relMSE %s against lavapipe's frame, above the sanity bound %g"
                        % (c.get("relmse"), SANITY_RELMSE))
    return fig, problems


def samebits(base, others):
    names = sorted(f for f in os.listdir(base) if f.startswith("frame") and f.endswith(".exr"))
    pool = {}
    for o in others:
        for f in os.listdir(o):
            if f.startswith("frame") and f.endswith(".exr"):
                pool.setdefault(f, []).append(os.path.join(o, f))
    differ, missing = [], []
    for n in names:
        paths = pool.get(n, [])
        if not paths:
            missing.append(n)
            continue
        with open(os.path.join(base, n), "rb") as f:
            a = f.read()
        for p in paths:
            with open(p, "rb") as f:
                if f.read() != a:
                    differ.append(n)
    extra = sorted(set(pool) - set(names))
    fig = {"files": len(names), "compared": len(names) - len(missing), "differ": differ,
           "missing": missing, "extra": extra}
    problems = []
    if not names:
        problems.append("no frame EXR in %s" % base)
    if differ:
        problems.append("%d of %d files differ: %s" % (len(differ), len(names), " ".join(differ[:6])))
    if missing:
        problems.append("missing: %s" % " ".join(missing[:6]))
    if extra:
        problems.append("not in the first render: %s" % " ".join(extra[:6]))
    return fig, problems


def parse_info(path):
    """The devices of `raybundle info`: '[i] NAME (default)' then indented 'key: value' lines."""
    devices = []
    with open(path, encoding="utf-8", errors="replace") as f:
        for line in f:
            m = re.match(r"^\[(\d+)\] (.*?)( \(default\))?\s*$", line)
            if m:
                devices.append({"index": int(m.group(1)), "name": m.group(2)})
                continue
            m = re.match(r"^\s+(type|api|driver|usable|timestamp period): (.*)$", line)
            if m and devices:
                devices[-1][m.group(1).replace(" ", "_")] = m.group(2).strip()
    return devices


def pick(path, selector):
    devices = parse_info(path)
    if selector:
        if selector.isdigit():
            hit = [d for d in devices if d["index"] == int(selector)]
        else:
            hit = [d for d in devices if selector.lower() in d["name"].lower()]
    else:
        hit = [d for d in devices if d.get("type", "").upper() != "CPU" and d.get("usable") == "yes"]
        hit = hit or [d for d in devices if d.get("type", "").upper() != "CPU"]
    if not hit:
        names = "; ".join("[%d] %s (%s)" % (d["index"], d["name"], d.get("type")) for d in devices)
        what = "no device matches '%s'" % selector if selector else "no device whose type is not CPU"
        return {"devices": devices}, ["%s among %s" % (what, names or "no device at all")]
    d = dict(hit[0])
    d["devices"] = len(devices)
    return d, []


def tables(doc):
    """The Markdown's tables as data: each validation, comparison and determinism cell's status
    (and figure), and per size and integrator the bench's GPU total, frame wall and their ratios
    to direct's."""
    steps = {s["id"]: s for s in doc["steps"]}
    st = doc.get("settings", {})
    t = {"validate": {}, "compare": {}, "determinism": {}, "bench": {}}
    for sc in st.get("validate", {}).get("scenes", ["demo", "cornell"]):
        t["validate"][sc] = {ig: (steps.get("validate/%s/%s" % (sc, ig)) or {}).get("status")
                             for ig in ("direct", "bdpt", "hybrid", "reference")}
        t["compare"][sc] = {}
        for ig in ("direct", "bdpt", "hybrid"):
            s = steps.get("compare/%s/%s" % (sc, ig)) or {}
            t["compare"][sc][ig] = {"status": s.get("status"),
                                    "relmse": s.get("figures", {}).get("relmse")}
    for ig in st.get("determinism", {}).get("integrators", []):
        t["determinism"][ig] = {w: (steps.get("determinism/%s/%s" % (ig, w)) or {}).get("status")
                                for w in ("twice", "chunks")}
    b = st.get("bench", {})
    for size in b.get("sizes", []):
        row = {}
        for ig in b.get("integrators", []):
            s = steps.get("bench/%s/%s" % (size, ig)) or {}
            f = s.get("figures", {}) if s.get("status") == "pass" else {}
            row[ig] = {"status": s.get("status"), "gpu_total_ms": f.get("gpu_total_ms"),
                       "wall_ms": f.get("wall_ms")}
        d = row.get("direct", {})
        for ig, r in row.items():
            for key, name in (("gpu_total_ms", "gpu_total_to_direct"), ("wall_ms", "wall_to_direct")):
                r[name] = (r[key] / d[key]) if r.get(key) and d.get(key) else None
        t["bench"][size] = row
    return t


# ---- Markdown -----------------------------------------------------------------------------


def esc(s):
    return str(s).replace("|", "\\|").replace("\n", " ")


def num(v, digits=None):
    """A figure for a table: 3 or 4 significant digits, exponent notation below 0.01."""
    del digits
    if v is None:
        return "–"
    if not isinstance(v, (int, float)):
        return esc(v)
    a = abs(v)
    if a == 0:
        return "0"
    if a < 0.01:
        return "%.2e" % v
    if a < 10:
        return "%.3f" % v
    if a < 100:
        return "%.2f" % v
    return "%.1f" % v


def secs(v):
    return "–" if v is None else "%.1f" % v


def cell(step, text=None):
    if step is None:
        return "–"
    st = step["status"]
    if st == "pass":
        return text if text is not None else "pass"
    if st == "fail":
        return "**FAIL**"
    if st == "running":
        return "interrupted" if step.get("_final") else "running"
    return "skipped"


def markdown(doc):
    final = doc.get("state") != "running"
    steps = {s["id"]: s for s in doc["steps"]}
    for s in doc["steps"]:
        s["_final"] = final
    L = []
    st = doc.get("settings", {})
    host = doc.get("host", {})
    dev = doc.get("device", {})
    L.append("# raybundle GPU check")
    L.append("")
    sm = doc.get("summary", {})
    L.append("State: **%s**, %s mode, %s s of a %s s budget; steps: %d passed, %d failed, %d skipped%s."
             % (doc.get("state"), doc.get("mode"), secs(doc.get("elapsed_s")), secs(doc.get("budget_s")),
                sm.get("pass", 0), sm.get("fail", 0), sm.get("skip", 0),
                ", %d interrupted" % sm["running"] if final and sm.get("running") else
                (", 1 running" if sm.get("running") else "")))
    L.append("Started %s, last written %s." % (doc.get("started_utc"), doc.get("updated_utc")))
    if doc.get("fatal"):
        L.append("")
        L.append("**Stopped early: %s.**" % esc(doc["fatal"]))
    L.append("")
    L.append("| | |")
    L.append("|---|---|")
    rows = [
        ("GPU (nvidia-smi)", host.get("nvidia_smi")),
        ("device under test", ("[%s] %s (%s), %s, API %s" % (dev.get("index"), dev.get("name"),
                                                         dev.get("type"), dev.get("driver"),
                                                         dev.get("api"))) if dev.get("name") else None),
        ("raybundle", "%s, from %s" % (doc.get("raybundle", {}).get("version"),
                                       doc.get("kit", {}).get("tarball"))),
        ("kernel", host.get("uname")),
        ("glibc", host.get("glibc")),
        ("CPU cores", host.get("cpus")),
        ("Vulkan loader", host.get("loader")),
        ("Vulkan driver files", host.get("icd")),
        ("validation layer", host.get("layer")),
    ]
    for k, v in rows:
        if v is not None:
            L.append("| %s | %s |" % (k, esc(v)))
    L.append("")

    setup = [s for s in doc["steps"] if s["group"] == "setup"]
    if setup:
        L.append("## Setup")
        L.append("")
        L.append("| step | status | wall s | note |")
        L.append("|---|---|---:|---|")
        for s in setup:
            L.append("| %s | %s | %s | %s |" % (s["id"], cell(s, "pass"), secs(s.get("wall_s")),
                                                 esc(s.get("note", ""))))
        L.append("")

    integ_v = ["direct", "bdpt", "hybrid", "reference"]
    v = st.get("validate", {})
    scenes = v.get("scenes", ["demo", "cornell"])
    L.append("## Validation")
    L.append("")
    L.append("Under the Khronos validation layer (`--validate`, synchronization validation on; any "
             "message fails the render), %s, frames %s; the reference (CPU) at %s spp on %s threads. "
             "A cell: the median frame's wall ms, or the failure (details below)."
             % (v.get("size"), v.get("frames"), v.get("spp"), v.get("threads")))
    L.append("")
    L.append("| scene | " + " | ".join(integ_v) + " |")
    L.append("|---|" + "---|" * len(integ_v))
    for sc in scenes:
        cells = []
        for ig in integ_v:
            s = steps.get("validate/%s/%s" % (sc, ig))
            txt = None
            if s and s["status"] == "pass":
                fg = s.get("figures", {})
                txt = "pass, %s ms" % num(fg.get("wall_ms_median"), 4)
                if fg.get("overflow"):
                    txt += " (node buffer overflow)"
            cells.append(cell(s, txt))
        L.append("| %s | %s |" % (sc, " | ".join(cells)))
    L.append("")

    c = st.get("compare", {})
    L.append("## Against lavapipe")
    L.append("")
    L.append("The device's frame against the kit's lavapipe frame of the same job (same job hash): "
             "%s, frame %s, beauty only (`layers: []`), `raybundle compare` (relMSE with eps %s). "
             "Bits need not match across drivers; a relMSE above %g fails (the demo's frame "
             "black is 0.4 to 0.5)." % (c.get("size"), c.get("frame"), "0.01", SANITY_RELMSE))
    L.append("")
    L.append("| scene | integrator | relMSE | RMSE | MAE | PSNR dB | max error (x, y) | status |")
    L.append("|---|---|---:|---:|---:|---:|---|---|")
    for sc in scenes:
        for ig in ["direct", "bdpt", "hybrid"]:
            s = steps.get("compare/%s/%s" % (sc, ig))
            r = steps.get("compare-render/%s/%s" % (sc, ig))
            fg = (s or {}).get("figures", {})
            if r is not None and r["status"] != "pass":
                s = r  # the render failed (or did not run): its status
            if s is None:
                L.append("| %s | %s | – | – | – | – | – | – |" % (sc, ig))
                continue
            mp = fg.get("max_error_pixel")
            L.append("| %s | %s | %s | %s | %s | %s | %s | %s |" % (
                sc, ig, num(fg.get("relmse")), num(fg.get("rmse")), num(fg.get("mae")),
                ("inf" if fg.get("psnr") is None and fg.get("relmse") == 0 else num(fg.get("psnr"), 4)),
                ("%s (%s, %s)" % (num(fg.get("max_error")), mp[0], mp[1]) if mp else "–"),
                cell(s)))
    L.append("")

    dt = st.get("determinism", {})
    L.append("## Determinism")
    L.append("")
    L.append("The %s job at %s, frames %s, rendered twice and once as two chunks (`--chunk 0/2`, "
             "`--chunk 1/2`); every EXR (hit-ratio images too) compared byte for byte with the "
             "first render." % (dt.get("scene"), dt.get("size"), dt.get("frames")))
    L.append("")
    L.append("| integrator | rendered twice | two chunks | files |")
    L.append("|---|---|---|---:|")
    for ig in dt.get("integrators", []):
        a = steps.get("determinism/%s/twice" % ig)
        b = steps.get("determinism/%s/chunks" % ig)
        # A render that failed leaves its comparison skipped; show the render's failure.
        renders = [steps.get("determinism/%s/%s" % (ig, r)) for r in ("run1", "run2", "chunk0", "chunk1")]
        rf = [r for r in renders if r is not None and r["status"] == "fail"]
        files = (a or {}).get("figures", {}).get("files")
        ta = cell(a, "same bits") if not (rf and (a is None or a["status"] == "skip")) else "**FAIL** (render)"
        tb = cell(b, "same bits") if not (rf and (b is None or b["status"] == "skip")) else "**FAIL** (render)"
        L.append("| %s | %s | %s | %s |" % (ig, ta, tb, files if files is not None else "–"))
    L.append("")

    b = st.get("bench", {})
    L.append("## GPU time per pass")
    L.append("")
    L.append("`raybundle bench` on the %s job, %s runs of frames %s at each size: per pass, the "
             "median over the runs of the run's mean GPU ms a frame (timestamp queries); a pass run "
             "several times a frame is summed (×N)." % (b.get("scene"), b.get("runs"), b.get("frames")))
    L.append("")
    for size in b.get("sizes", []):
        figs = {}
        stp = {}
        for ig in b.get("integrators", []):
            s = steps.get("bench/%s/%s" % (size, ig))
            stp[ig] = s
            if s and s["status"] == "pass":
                figs[ig] = s.get("figures", {})
        igs = b.get("integrators", [])
        L.append("### %s" % size)
        L.append("")
        L.append("| pass | " + " | ".join(igs) + " |")
        L.append("|---|" + "---:|" * len(igs))
        order = merge_order([figs[i].get("pass_order", []) for i in igs if i in figs])
        for p in order:
            cells = []
            for ig in igs:
                fg = figs.get(ig)
                if fg is None or p not in fg.get("passes_ms", {}):
                    cells.append("" if fg is not None else "–")
                    continue
                n = fg.get("pass_counts", {}).get(p, 1)
                cells.append(num(fg["passes_ms"][p], 4) + (" (×%d)" % n if n and n > 1 else ""))
            L.append("| %s | %s |" % (p, " | ".join(cells)))
        def row(label, key, fmt=lambda v: num(v, 4)):
            cells = []
            for ig in igs:
                fg = figs.get(ig)
                cells.append(fmt(fg.get(key)) if fg else cell(stp.get(ig)))
            L.append("| %s | %s |" % (label, " | ".join(cells)))
        row("**GPU total**", "gpu_total_ms")
        row("frame wall ms", "wall_ms")
        d = figs.get("direct")
        for label, key in (("GPU total / direct", "gpu_total_ms"), ("frame wall / direct", "wall_ms")):
            cells = []
            for ig in igs:
                fg = figs.get(ig)
                if fg and d and d.get(key):
                    cells.append("%.2f" % (fg[key] / d[key]))
                else:
                    cells.append("–")
            L.append("| %s | %s |" % (label, " | ".join(cells)))
        if any(f.get("overflow") for f in figs.values()):
            L.append("| node buffer overflow | %s |" % " | ".join(
                ("yes" if figs.get(ig, {}).get("overflow") else "no") for ig in igs))
        L.append("")

    bad = [s for s in doc["steps"] if s["status"] == "fail" or (s["status"] == "running" and final)]
    if bad:
        L.append("## Failures")
        L.append("")
        for s in bad:
            what = "exit %s" % s.get("rc") if s["status"] == "fail" else "interrupted"
            L.append("### %s (%s, %s s)" % (s["id"], what, secs(s.get("wall_s"))))
            L.append("")
            if s.get("note"):
                L.append(esc(s["note"]))
                L.append("")
            L.append("```")
            L.append("$ " + s.get("cmd", ""))
            L.extend(s.get("error_tail", []))
            L.append("```")
            L.append("")
    skipped = [s for s in doc["steps"] if s["status"] == "skip"]
    if skipped:
        L.append("## Skipped")
        L.append("")
        for s in skipped:
            L.append("- %s: %s" % (s["id"], esc(s.get("note", ""))))
        L.append("")
    for s in doc["steps"]:
        s.pop("_final", None)
    return "\n".join(L) + "\n"


# ---- commands -----------------------------------------------------------------------------


def emit(fig, problems):
    json.dump(fig, sys.stdout)
    sys.stdout.write("\n")
    for p in problems:
        sys.stderr.write(p + "\n")
    return 1 if problems else 0


def main(argv):
    if len(argv) < 2:
        sys.stderr.write(__doc__)
        return 2
    cmd, args = argv[1], argv[2:]
    if cmd == "init":
        out, mode, budget, settings = args
        doc = {"format": "raybundle-gpu-check 1", "state": "running", "mode": mode,
               "budget_s": float(budget), "started_utc": now(), "started_epoch": time.time(),
               "elapsed_s": 0,
               "settings": json.loads(settings), "kit": {}, "host": {}, "raybundle": {},
               "device": {}, "steps": []}
        save(out, doc)
        return 0
    if cmd == "render-figures":
        return emit(*render_figures(args[0], args[1], args[2] if len(args) > 2 else None))
    if cmd == "bench-figures":
        return emit(*bench_figures(args[0], args[1] if len(args) > 1 else None))
    if cmd == "compare-figures":
        return emit(*compare_figures(*args))
    if cmd == "pick":
        return emit(*pick(args[0], args[1] if len(args) > 1 else ""))
    if cmd == "jget":
        v = get_path(read_json(args[0]), args[1])
        print(v if not isinstance(v, (dict, list)) else json.dumps(v))
        return 0
    if cmd == "samebits":
        return emit(*samebits(args[0], args[1:]))
    out = args[0]
    doc = load(out)
    if cmd == "get":
        v = get_path(doc, args[1])
        print(v if not isinstance(v, (dict, list)) else json.dumps(v))
        return 0
    if cmd == "md":
        save(out, doc)
        return 0
    if cmd == "set":
        set_path(doc, args[1], args[2])
    elif cmd == "set-json":
        set_path(doc, args[1], json.loads(args[2]))
    elif cmd == "set-file":
        try:
            with open(args[2], encoding="utf-8", errors="replace") as f:
                text = f.read()
        except OSError as e:
            text = "(unreadable: %s)" % e
        set_path(doc, args[1], text.rstrip("\n"))
    elif cmd == "start":
        sid, group, command = args[1], args[2], args[3]
        old = find_step(doc, sid)
        if old:
            doc["steps"].remove(old)
        doc["steps"].append({"id": sid, "group": group, "cmd": command, "status": "running",
                             "started_utc": now()})
    elif cmd == "end":
        sid, status, rc, wall = args[1], args[2], args[3], args[4]
        s = find_step(doc, sid)
        if s is None:
            sys.stderr.write("report.py: no step %s\n" % sid)
            return 2
        s["status"] = status
        s["rc"] = int(rc) if rc.lstrip("-").isdigit() else rc
        s["wall_s"] = round(float(wall), 3)
        rest = args[5:]
        i = 0
        while i < len(rest):
            opt, val = rest[i], rest[i + 1]
            i += 2
            if opt == "--stderr" and status != "pass":
                s["error_tail"] = tail(val)
            elif opt == "--note" and val:
                s["note"] = val
            elif opt == "--figures" and val:
                try:
                    with open(val, encoding="utf-8") as f:
                        txt = f.read().strip()
                    if txt:
                        s["figures"] = json.loads(txt)
                except (OSError, ValueError) as e:
                    s.setdefault("note", "figures unreadable: %s" % e)
    elif cmd == "skip":
        sid, group, reason = args[1], args[2], args[3]
        old = find_step(doc, sid)
        if old:
            doc["steps"].remove(old)
        doc["steps"].append({"id": sid, "group": group, "cmd": "", "status": "skip",
                             "note": reason})
    elif cmd == "finish":
        doc["elapsed_s"] = round(time.time() - doc.get("started_epoch", time.time()), 1)
        doc["state"] = args[1]
        doc["finished_utc"] = now()
    else:
        sys.stderr.write("report.py: unknown command %s\n" % cmd)
        return 2
    save(out, doc)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
