#!/usr/bin/env python3
"""Regenerates the tables of docs/benchmarks.md from one run of bench-peers/run_all.sh.

Inputs (all written by that run, into RESULTS_DIR):
- criterion's estimates under CRITERION_DIR, each with its benchmark.json: `<id>/new/` for
  rayon's default pool, or `<id>/base/` when the bench was run again with RAYON_NUM_THREADS=1
  and `--save-baseline one-thread` (criterion then moves the first run to `base/`, and the
  second is in `new/` and `one-thread/`);
- RESULTS_DIR/results-SECTION.jsonl: the peers' and the `nurbspring` binary's timings
  (results.py), one file per section of the run;
- RESULTS_DIR/run.json: the machine, versions and the load at each section's start and end.

Each table sits between `<!-- generated: NAME -->` and `<!-- /generated: NAME -->` in the
document; everything outside those markers is left as it is. A figure missing from the run is
written as "not measured", never carried over from an earlier run.

    python3 bench-peers/tables.py RESULTS_DIR CRITERION_DIR [docs/benchmarks.md]
"""
import json
import math
import os
import re
import statistics
import sys


def load_criterion(root):
    """{(full_id, baseline): {"mid": s, "lo": s, "hi": s, "throughput": {...} or None}}."""
    out = {}
    for dirpath, _dirs, files in os.walk(root):
        if "estimates.json" not in files or "benchmark.json" not in files:
            continue
        baseline = os.path.basename(dirpath)
        if baseline in ("change", "report"):
            continue
        with open(os.path.join(dirpath, "benchmark.json")) as f:
            meta = json.load(f)
        with open(os.path.join(dirpath, "estimates.json")) as f:
            est = json.load(f)
        # criterion's middle estimate: the slope of the linear sampling when it has one.
        e = est.get("slope") or est["mean"]
        ci = e["confidence_interval"]
        out[(meta["full_id"], baseline)] = {
            "mid": e["point_estimate"] * 1e-9,
            "lo": ci["lower_bound"] * 1e-9,
            "hi": ci["upper_bound"] * 1e-9,
            "throughput": meta.get("throughput"),
        }
    return out


def load_results(results_dir):
    """{(source, bench): [records]}; a job timed in several lines (several runs) keeps them all."""
    out = {}
    for name in sorted(os.listdir(results_dir)):
        if not (name.startswith("results-") and name.endswith(".jsonl")):
            continue
        with open(os.path.join(results_dir, name)) as f:
            for line in f:
                if line.strip():
                    r = json.loads(line)
                    out.setdefault((r["source"], r["bench"]), []).append(r)
    return out


def fmt_time(s):
    """Three significant digits in the unit that suits."""
    if s is None:
        return "not measured"
    for unit, scale in (("s", 1.0), ("ms", 1e-3), ("µs", 1e-6), ("ns", 1e-9)):
        if s >= scale or unit == "ns":
            v = s / scale
            digits = 0 if v >= 100 else (1 if v >= 10 else 2)
            return f"{v:.{digits}f} {unit}"


def fmt_ratio(r):
    if r is None:
        return "—"
    return f"{r:.2f}×" if r < 10 else f"{r:.1f}×" if r < 100 else f"{r:.0f}×"


class Run:
    def __init__(self, results_dir, criterion_dir):
        self.crit = load_criterion(criterion_dir)
        self.res = load_results(results_dir)
        with open(os.path.join(results_dir, "run.json")) as f:
            self.info = json.load(f)

    # ---- lookups
    def c(self, full_id, baseline="new", per_element=False):
        """Criterion's estimate; with per_element, divided by the benchmark's element count
        (the per-point figures of the geometry benches, which time 4096 points an iteration)."""
        # A bench run twice in one session (rayon's pool, then one thread with
        # `--save-baseline one-thread`) ends with the one-thread run in both `new` and
        # `one-thread`, and criterion has moved the first run to `base`.
        if baseline == "new" and (full_id, "one-thread") in self.crit:
            baseline = "base"
        e = self.crit.get((full_id, baseline))
        if e and per_element:
            n = (e["throughput"] or {}).get("Elements", 1)
            e = dict(e, mid=e["mid"] / n, lo=e["lo"] / n, hi=e["hi"] / n)
        return e

    def cmid(self, full_id, baseline="new", per_element=False):
        e = self.c(full_id, baseline, per_element)
        return e["mid"] if e else None

    def ccell(self, full_id, baseline="new", bold=False, per_element=False):
        e = self.c(full_id, baseline, per_element)
        if not e:
            return "not measured"
        mid = fmt_time(e["mid"])
        if bold:
            mid = f"**{mid}**"
        return f"{mid} ({fmt_time(e['lo'])} – {fmt_time(e['hi'])})"

    def bandwidth(self, full_id, baseline="new"):
        e = self.c(full_id, baseline)
        if not e or not e["throughput"] or "Bytes" not in e["throughput"]:
            return None
        return e["throughput"]["Bytes"] / e["mid"] / 1e9

    def peer(self, source, bench):
        rs = self.res.get((source, bench))
        if not rs:
            return None
        if len(rs) == 1:
            return {"min": rs[0]["min_s"], "median": rs[0]["median_s"], "n": len(rs[0]["times_s"]),
                    "info": rs[0]["info"]}
        times = [t for r in rs for t in r["times_s"]]
        return {"min": min(times), "median": statistics.median(times), "n": len(times),
                "info": rs[0]["info"]}

    def pcell(self, source, bench):
        p = self.peer(source, bench)
        if not p:
            return "not measured"
        return f"{fmt_time(p['min'])} min, {fmt_time(p['median'])} median ({p['n']} runs)"

    def section(self, name):
        s = self.info.get("sections", {}).get(name)
        if not s:
            return f"*Section `{name}` was not run.*"
        day = f"{s['date']} " if s.get("date") else ""
        return (f"Run {day}{s['start']} – {s['end']} UTC; load average {s['load_start']:.2f} at the start, "
                f"{s['load_end']:.2f} at the end.")

    # ---- tables
    def header(self):
        i = self.info
        sections = i.get("sections", {})
        # A section is from an earlier run when it started before this one (same day) or on an
        # earlier day (a section without a date is from before dates were recorded).
        def earlier(v):
            day = v.get("date")
            return day is None or day < i["date"] or (day == i["date"] and v["start"] < i["start"])
        rerun = [n for n, v in sections.items() if earlier(v)]
        days = sorted({sections[n].get("date") or "an earlier day" for n in rerun})
        when = (f"one run ({i['start']} – {i['end']} UTC)" if not rerun else
                f"one run folder: {', '.join(n for n in sections if n not in rerun)} rerun at "
                f"{i['start']} – {i['end']} UTC, the other sections ({', '.join(rerun)}) earlier "
                f"({', '.join(days)})")
        lines = [f"Generated by `bench-peers/run_all.sh` on {i['date']} from {when}; each table "
                 f"gives its own section's time and load.",
                 "",
                 f"- Machine: {i['cpu']}, {i['cpus']} CPUs, {i['memory']}; {i['kernel']}.",
                 f"- Toolchain: {i['rustc']}; release profile (`lto = \"thin\"`, `codegen-units = 16`).",
                 f"- Peers: {i.get('peers', 'not recorded')}.",
                 f"- Load average: {i['load_start']:.2f} at the start, {i['load_end']:.2f} at the end."]
        return "\n".join(lines)

    def targets(self):
        rows = []

        def add(target, measured, ratio, goal, met):
            verdict = "not measured" if met is None else ("**met**" if met else "**missed**")
            rows.append(f"| {target} | {measured} | {fmt_ratio(ratio) if ratio else '—'} | {goal} | {verdict} |")

        modal = self.cmid("derive/modal_33x33")
        add("`derive` default derivation, 33 × 33 net", fmt_time(modal), None, "< 1 s",
            None if modal is None else modal < 1.0)
        for label, name, goal in (("paper derivation, 17² / 33² (all candidates)", "derive_paper_17_33_c0", 5.0),
                                  ("paper derivation, 17² / 33² (12 candidates)", "derive_paper_17_33_c12", 5.0),
                                  ("paper derivation, 33² / 65² (12 candidates)", "derive_paper_33_65_c12", 30.0),
                                  ("`nurbspring paper`", "paper", 0.3)):
            t = self.binary(name)
            if self.binary_failed(name):
                rows.append(f"| {label} | fails (see below) | — | < {goal:g} s | **missed** |")
                continue
            add(label, fmt_time(t), None, f"< {goal:g} s", None if t is None else t < goal)
        # Growth in control points between two nets: t ∝ N^p, N the control points.
        for label, (small, n_small), (large, n_large) in (
                ("time growth in control points, default derivation, 65² → 129² net (lowest 200 modes)",
                 ("derive_default_65", 65 ** 2), ("derive_default_129", 129 ** 2)),
                ("time growth in control points, default derivation, 33² → 65² net (every mode → lowest 200)",
                 ("derive_default_33", 33 ** 2), ("derive_default_65", 65 ** 2)),
                ("time growth in control points, paper derivation, 17² / 33² → 33² / 65² (12 candidates)",
                 ("derive_paper_17_33_c12", 17 ** 2), ("derive_paper_33_65_c12", 33 ** 2))):
            t1, t2 = self.binary(small), self.binary(large)
            if t1 is None or t2 is None or self.binary_failed(small) or self.binary_failed(large):
                rows.append(f"| {label} | not measured | — | near 1 | not measured |")
                continue
            p = math.log(t2 / t1) / math.log(n_large / n_small)
            rows.append(f"| {label} | {fmt_time(t1)} → {fmt_time(t2)}: t ∝ N^{p:.2f} | — | exponent near 1 | "
                        f"{'**met**' if p <= 1.2 else '**missed**'} |")
        fast = self.cmid("dnurbs_128x128_bicubic/assemble_scalar (S_M, S_K, N x N)")
        gen = self.cmid("dnurbs_128x128_bicubic/assemble_scalar, unequal weights (Gauss-point kernel, incl. pattern)")
        gismo = self.gismo_total()
        kron = (self.peer("numpy-kronecker", "mass_stiffness") or {}).get("min")
        add("assembly, Kronecker path, vs G+Smo", fmt_time(fast), ratio(gismo, fast), "≥ 10×",
            meets(ratio(gismo, fast), 10))
        add("assembly, Kronecker path, vs NumPy Kronecker", fmt_time(fast), ratio(kron, fast), "> 1×",
            meets(ratio(kron, fast), 1.0 + 1e-12))
        add("assembly, general path, vs G+Smo", fmt_time(gen), ratio(gismo, gen), "≥ 4×",
            meets(ratio(gismo, gen), 4))
        fused2 = self.cmid("msm/symplectic_euler_step/256x256")
        fused1 = self.cmid("msm/symplectic_euler_step/256x256", "one-thread")
        warp = (self.peer("warp", "step_256x256") or {}).get("median")
        add("explicit step 256², 2 threads, vs Warp CPU (median)", fmt_time(fused2), ratio(warp, fused2), "≥ 2×",
            meets(ratio(warp, fused2), 2))
        add("explicit step 256², 1 thread, vs Warp CPU (median)", fmt_time(fused1), ratio(warp, fused1), "≥ 1.2×",
            meets(ratio(warp, fused1), 1.2))
        bw = self.bandwidth("msm/symplectic_euler_step/256x256")
        triad = self.bandwidth("memory/triad_3x3MiB")
        add("explicit step 256², achieved bandwidth vs cache-sized triad",
            "not measured" if bw is None else f"{bw:.1f} GB/s (triad {triad:.1f})" if triad else f"{bw:.1f} GB/s",
            ratio(triad, bw), "within 1.5×", None if not (bw and triad) else triad / bw <= 1.5)
        # The arithmetic floor: no exact f64 step is faster than the square roots and divisions
        # of its springs, whatever the bandwidth.
        floor = self.cmid("msm/spring_arithmetic/256x256")
        traffic = (self.c("msm/symplectic_euler_step/256x256") or {}).get("throughput") or {}
        bound = traffic.get("Bytes", 0) / (triad * 1e9) if triad else None
        if fused2 and floor and bound:
            rows.append(f"| explicit step 256², against its two bounds: bandwidth (bytes / cache triad) and "
                        f"arithmetic (√ and ÷ of every spring) | {fmt_time(fused2)}; bounds {fmt_time(bound)} "
                        f"and {fmt_time(floor)} | {fused2 / floor:.2f}× the arithmetic bound | — | the arithmetic "
                        f"bound alone is {floor / bound:.2f}× the bandwidth bound |")
        else:
            rows.append("| explicit step 256², against its two bounds | not measured | — | — | not measured |")
        be = self.cmid("msm/backward_euler_step/128x128")
        scipy = (self.peer("scipy", "backward_euler_step_128x128") or {}).get("median")
        add("backward-Euler step 128², vs SciPy", fmt_time(be), ratio(scipy, be), "≥ 30×", meets(ratio(scipy, be), 30))
        fac = self.cmid("msm/newton_factorization/128x128")
        measured = f"{fmt_time(be)} = {be / fac:.2f} × {fmt_time(fac)}" if be and fac else "not measured"
        verdict = f"{be / fac:.2f} factorizations" if be and fac else "not measured"
        rows.append(f"| backward-Euler step 128², in numeric factorizations | {measured} | — | "
                    f"a small multiple | {verdict} |")
        pt = self.cmid("point/rational_bicubic", per_element=True)
        curvo = self.cmid("peers_point/curvo", per_element=True)
        add("surface point, vs curvo", fmt_time(pt), ratio(curvo, pt), "≥ 3×", meets(ratio(curvo, pt), 3))
        grid = self.cmid("grid/1000x1000_one_thread")
        splipy = (self.peer("splipy", "grid_1000x1000") or {}).get("min")
        add("1000² grid, one thread, vs splipy (min)", fmt_time(grid), ratio(splipy, grid), "≥ 3×",
            meets(ratio(splipy, grid), 3))
        head = ["| issue 12 target | nurbspring | ratio | goal | verdict |", "|---|---|---|---|---|"]
        return "\n".join(head + rows)

    def binary(self, bench):
        bins = [k for k in self.res if k[1] == bench]
        if not bins:
            return None
        # the binary under test (BIN): the first one recorded
        p = self.peer(*bins[0])
        return p["median"]

    def binary_failed(self, bench):
        bins = [k for k in self.res if k[1] == bench]
        return bool(bins) and any(r["info"].get("failed") for r in self.res[bins[0]])

    def gismo_total(self):
        m, b = self.peer("gismo", "mass"), self.peer("gismo", "biharmonic")
        return m["min"] + b["min"] if m and b else None

    def geometry(self):
        pt = self.cmid("point/rational_bicubic", per_element=True)
        curvo = self.cmid("peers_point/curvo", per_element=True)
        grid1 = self.cmid("grid/1000x1000_one_thread")
        splipy = self.peer("splipy", "grid_1000x1000")
        curvo_grid = self.cmid("peers_grid_1000x1000/curvo_regular_sample_points")
        ng1 = self.cmid("peers_grid_1000x1000/nurbspring_grid_one_thread")
        rows = [
            "| benchmark | nurbspring-geom | peer | peer / nurbspring |",
            "|---|---|---|---|",
            f"| point, rational bicubic (per point) | {self.ccell('point/rational_bicubic', bold=True, per_element=True)} | "
            f"curvo `point_at`: {self.ccell('peers_point/curvo', per_element=True)} | **{fmt_ratio(ratio(curvo, pt))}** |",
            f"| same, inside the peers bench | {self.ccell('peers_point/nurbspring', per_element=True)} | — | "
            f"{fmt_ratio(ratio(curvo, self.cmid('peers_point/nurbspring', per_element=True)))} (same group) |",
            f"| grid 1000 × 1000, one thread | {self.ccell('grid/1000x1000_one_thread', bold=True)} | splipy: "
            f"{self.pcell('splipy', 'grid_1000x1000')} | **{fmt_ratio(ratio(splipy and splipy['min'], grid1))}** (min), "
            f"{fmt_ratio(ratio(splipy and splipy['median'], grid1))} (median) |",
            f"| grid 1000 × 1000, one thread, peers bench | {self.ccell('peers_grid_1000x1000/nurbspring_grid_one_thread')} | "
            f"curvo `regular_sample_points`: {self.ccell('peers_grid_1000x1000/curvo_regular_sample_points')} | "
            f"{fmt_ratio(ratio(curvo_grid, ng1))} |",
            f"| grid 1000 × 1000, rayon's pool | {self.ccell('grid/1000x1000')} | — | — |",
            f"| point and both tangents (`derivatives(u, v, 1)`) | {self.ccell('point/rational_bicubic_derivatives1', per_element=True)} | "
            f"splipy scattered (vectorised, per point): {self.pcell('splipy', 'point_scattered')} | — |",
        ]
        return self.section("geometry") + "\n\n" + "\n".join(rows)

    def assembly(self):
        g = "dnurbs_128x128_bicubic/"
        gismo = self.gismo_total()
        kron = self.peer("numpy-kronecker", "mass_stiffness")
        kmin = kron["min"] if kron else None
        gm, gb = self.peer("gismo", "mass"), self.peer("gismo", "biharmonic")
        gcol = (f"G+Smo mass + biharmonic: {fmt_time(gismo)} min ({fmt_time(gm['min'])} + {fmt_time(gb['min'])})"
                if gismo else "G+Smo: not measured")
        kcol = f"NumPy Kronecker M + K: {self.pcell('numpy-kronecker', 'mass_stiffness')}"
        rows = [f"| job (M and K, pattern included) | nurbspring | {gcol} | {kcol} |", "|---|---|---|---|"]
        for label, bench, with_kron in (
                ("B-spline, parameter domain: Kronecker form (`assemble_scalar`)", "assemble_scalar (S_M, S_K, N x N)", True),
                ("unequal weights, Gauss-point kernel", "assemble_scalar, unequal weights (Gauss-point kernel, incl. pattern)", False),
                ("area integration, Gauss-point kernel", "assemble_scalar, area integration (Gauss-point kernel, incl. pattern)", False)):
            t = self.cmid(g + bench)
            rows.append(f"| {label} | {self.ccell(g + bench, bold=True)} | **{fmt_ratio(ratio(gismo, t))}** | "
                        f"{'**' + fmt_ratio(ratio(kmin, t)) + '**' if with_kron else '— (no shortcut)'} |")
        rows += ["", "| benchmark | rayon's pool | one thread |", "|---|---|---|"]
        for label, bench in (
                ("pattern only (`Assembler::new`)", "pattern only (Assembler::new, once per knot vectors)"),
                ("values, pattern reused (`Assembler::assemble_scalar`)", "Assembler::assemble_scalar (pattern reused)"),
                ("values, area integration, automatic rule", "Assembler::assemble_scalar, area integration (Gauss-point kernel)"),
                ("`assemble` on 3N dofs (M, D, K, f), pattern included", "assemble (M, D, K, f on 3N dofs)"),
                ("weights as unknowns, 32 × 32 elements, pattern included", "assemble, weights as dofs, 32 x 32 elements (4N dofs, incl. pattern)"),
                ("Terzopoulos–Qin step (factored)", "terzopoulos-qin step (factored)")):
            rows.append(f"| {label} | {self.ccell(g + bench)} | {self.ccell(g + bench, 'one-thread')} |")
        scal = []
        for e in (32, 64, 128):
            scal.append(f"{fmt_time(self.cmid(f'dnurbs_scaling/pattern (Assembler::new)/{e}'))} / "
                        f"{fmt_time(self.cmid(f'dnurbs_scaling/assemble_scalar (pattern reused)/{e}'))}")
        rows.append(f"| pattern / values at 32² · 64² · 128² elements (`dnurbs_scaling`) | {' · '.join(scal)} | — |")
        return self.section("assembly") + "\n\n" + "\n".join(rows)

    def derive_modal(self):
        return (self.section("derive-modal") + "\n\n| benchmark | time (criterion middle estimate, 95 % interval) |\n"
                f"|---|---|\n| `derive/modal_33x33` | {self.ccell('derive/modal_33x33', bold=True)} |")

    def derive_paper(self):
        rows = ["| job | min | median | runs | max RSS |", "|---|---|---|---|---|"]
        for label, bench in (("`nurbspring paper`", "paper"),
                             ("paper derivation, 7² cps / 9² lattice, all candidates", "derive_paper_7_9_c0"),
                             ("same, 9² / 17², all candidates", "derive_paper_9_17_c0"),
                             ("same, 17² / 33², all candidates", "derive_paper_17_33_c0"),
                             ("same, 17² / 33², 12 candidates", "derive_paper_17_33_c12"),
                             ("same, 33² / 65², 12 candidates", "derive_paper_33_65_c12"),
                             ("default derivation, 9² cps / 9² lattice", "derive_default_9"),
                             ("same, 17² / 17²", "derive_default_17"),
                             ("same, 33² / 33²", "derive_default_33"),
                             ("same, 65² / 65² (lowest 200 modes)", "derive_default_65"),
                             ("same, 97² / 97² (lowest 200 modes)", "derive_default_97"),
                             ("same, 129² / 129² (lowest 200 modes)", "derive_default_129")):
            bins = [k for k in self.res if k[1] == bench]
            if not bins:
                rows.append(f"| {label} | not measured | | | |")
                continue
            rs = self.res[bins[0]]
            times = [r["times_s"][0] for r in rs]
            failed = [r for r in rs if r["info"].get("failed")]
            if failed:
                rows.append(f"| {label} | **fails** in all {len(failed)} of {len(rs)} runs, after "
                            f"{fmt_time(min(times))} – {fmt_time(max(times))}: "
                            f"`{failed[0]['info'].get('error', '')}` | | | |" if len(failed) == len(rs) else
                            f"| {label} | **fails** in {len(failed)} of {len(rs)} runs | | | |")
                continue
            rss = max(r["info"].get("max_rss_kb", 0) for r in rs) / 1024
            rows.append(f"| {label} | **{fmt_time(min(times))}** | {fmt_time(statistics.median(times))} | "
                        f"{len(times)} | {rss:.0f} MiB |")
        return self.section("derive-paper") + "\n\n" + "\n".join(rows)

    def msm_step(self):
        warp = self.peer("warp", "step_256x256")
        rows = ["| benchmark | rayon's pool | one thread |", "|---|---|---|"]
        for label, bench in (("fused step (`symplectic_euler_step`)", "msm/symplectic_euler_step/256x256"),
                             ("arithmetic floor (√ and ÷ of every spring only)", "msm/spring_arithmetic/256x256"),
                             ("generic step", "msm/symplectic_euler_step_generic/256x256"),
                             ("internal force only (generic)", "msm/internal_force/256x256")):
            cells = []
            for base in ("new", "one-thread"):
                cell = self.ccell(bench, base, bold=bench.endswith("step/256x256"))
                bw = self.bandwidth(bench, base)
                cells.append(cell + (f", {bw:.1f} GB/s" if bw else ""))
            rows.append(f"| {label} | {cells[0]} | {cells[1]} |")
        for label, bench in (("triad 3 × 128 MiB", "memory/triad_3x128MiB"), ("triad 3 × 3 MiB", "memory/triad_3x3MiB")):
            cells = [f"{self.bandwidth(bench, b):.1f} GB/s" if self.bandwidth(bench, b) else "not measured"
                     for b in ("new", "one-thread")]
            rows.append(f"| {label} | {cells[0]} | {cells[1]} |")
        fused = [self.cmid("msm/symplectic_euler_step/256x256", b) for b in ("new", "one-thread")]
        peers = [("Warp CPU f32", "warp", "step_256x256"), ("Taichi CPU f64", "taichi", "step_256x256"),
                 ("NumPy f64 (bincount)", "numpy", "step_256x256_bincount")]
        prow = ["", "| peer (one process, its own threading) | median (min) | peer median / fused, rayon's pool · one thread |",
                "|---|---|---|"]
        for label, src, bench in peers:
            p = self.peer(src, bench)
            if not p:
                prow.append(f"| {label} | not measured | — |")
                continue
            prow.append(f"| {label} | {fmt_time(p['median'])} ({fmt_time(p['min'])}) | "
                        f"**{fmt_ratio(ratio(p['median'], fused[0]))}** · **{fmt_ratio(ratio(p['median'], fused[1]))}** |")
        be = self.cmid("msm/backward_euler_step/128x128")
        fac = self.cmid("msm/newton_factorization/128x128")
        scipy = self.peer("scipy", "backward_euler_step_128x128")
        irow = ["", "| 128 × 128 lattice, Δt = 1e-3 | nurbspring | SciPy (Newton + SuperLU) | SciPy / nurbspring |",
                "|---|---|---|---|",
                f"| backward-Euler step | {self.ccell('msm/backward_euler_step/128x128', bold=True)} | "
                f"{self.pcell('scipy', 'backward_euler_step_128x128')}"
                f"{', %.1f Newton iterations a step' % scipy['info']['newton_iterations'] if scipy else ''} | "
                f"**{fmt_ratio(ratio(scipy and scipy['median'], be))}** (medians) |",
                f"| one numeric factorization of `M + Δt² K_T` | {self.ccell('msm/newton_factorization/128x128')} | — | — |",
                f"| one solve with that factor | {self.ccell('msm/newton_solve/128x128')} | — | — |",
                f"| tangent stiffness `K_T` | {self.ccell('msm/tangent_stiffness/128x128')} | — | — |",
                f"| step / factorization | {be / fac:.2f}" if be and fac else "| step / factorization | not measured"]
        sol = self.cmid("msm/newton_solve/128x128")
        irow[-1] += " | — | — |"
        irow.append(f"| factorization / solve | {fac / sol:.0f}" if fac and sol else "| factorization / solve | not measured")
        irow[-1] += " | — | — |"
        return self.section("msm") + "\n\n" + "\n".join(rows + prow + irow)


def ratio(peer, ours):
    return peer / ours if peer and ours else None


def meets(r, goal):
    return None if r is None else r >= goal


def splice(doc, name, body):
    pat = re.compile(rf"(<!-- generated: {re.escape(name)} -->\n).*?(<!-- /generated: {re.escape(name)} -->)", re.S)
    if not pat.search(doc):
        raise SystemExit(f"docs/benchmarks.md: no block `<!-- generated: {name} -->` ... `<!-- /generated: {name} -->`")
    return pat.sub(lambda m: m.group(1) + body.rstrip() + "\n" + m.group(2), doc)


def main():
    if len(sys.argv) < 3:
        raise SystemExit(__doc__)
    run = Run(sys.argv[1], sys.argv[2])
    path = sys.argv[3] if len(sys.argv) > 3 else os.path.join(os.path.dirname(__file__), "..", "docs", "benchmarks.md")
    with open(path) as f:
        doc = f.read()
    for name, make in (("run", run.header), ("targets", run.targets), ("geometry", run.geometry),
                       ("assembly", run.assembly), ("derive-modal", run.derive_modal),
                       ("derive-paper", run.derive_paper), ("msm", run.msm_step)):
        doc = splice(doc, name, make())
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write(doc)
    os.replace(tmp, path)
    print(f"{path}: tables regenerated from {sys.argv[1]}")


if __name__ == "__main__":
    main()
