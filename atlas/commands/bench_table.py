"""``atlas bench``'s plain-text table: the JSON result of :func:`atlas.commands.bench.run_bench`
as the lines ``atlas bench`` prints (the map, bulk, torque, scaling, thread, plotting, JIT and
end-to-end rows, the rows of other modules (:data:`atlas.commands.bench.MORE_ROWS`), and the
summary against the targets)."""

from __future__ import annotations

from atlas.commands.bench_kernels import MAP_N

__all__ = ["format_table"]


def _fmt_bytes(b) -> str:
    return "n/a" if b is None else f"{b / 2**20:.0f} MB" if b < 2**30 else f"{b / 2**30:.2f} GB"




def _fmt_rows(rows, side):
    lines = [f"  {'variant':62s} {'steps/s':>10s} {'orbits/s':>10s} {f'{side}² map':>10s} "
             f"{'× atlas':>8s}"]
    for r in rows:
        lines.append(f"  {r['variant']:62s} {r['steps_per_s']:10.3g} {r['orbits_per_s']:10.3g} "
                     f"{_fmt_s(r['map_s']):>10s} {r['ratio_to_atlas']:8.3g}"
                     + (f"  ({r['note']})" if r["note"] else ""))
    return lines


def _more_lines(more: dict) -> list[str]:
    """The rows of other modules (:func:`atlas.commands.bench.more_rows`)."""
    lines = []
    for section in more.values():
        if "skipped" in section:
            lines.append(f"{section['title']}: skipped ({section['skipped']})")
            continue
        lines.append(section["title"])
        for r in section["rows"]:
            if not {"variant", "wall_s", "ratio"} <= r.keys():  # not the documented shape:
                lines.append("  " + ", ".join(f"{k} {_fmt_value(v)}" for k, v in r.items()))
                continue  # shown as it came
            rate = (f" {r['orbits_per_s']:10.3g} orbits/s" if "orbits_per_s" in r else "")
            against = f" {r['against']}" if r.get("against") else ""
            lines.append(f"  {r['variant']:48s} {_fmt_s(r['wall_s']):>9s}{rate} "
                         f"{r['ratio']:6.2f}×{against}"
                         + (f"  ({r['note']})" if r.get("note") else ""))
    return lines


def _fmt_value(v) -> str:
    return f"{v:.3g}" if isinstance(v, float) else str(v)


def _fmt_s(s):
    if s is None:
        return "n/a"
    return f"{s * 1e3:.0f} ms" if s < 1 else f"{s:.3g} s" if s < 600 else f"{s / 60:.3g} min"


def format_table(result: dict) -> str:
    """The benchmark as a plain-text table."""
    m, s = result["machine"], result["summary"]
    side = result["map"].get("side", MAP_N)
    lines = [f"CPU: {m['cpu']}, {m['cores']} cores ({m['numba_threads']} numba threads); "
             f"python {m['python']}, numpy {m['numpy']}, numba {m['numba']}, "
             f"llvmlite {m['llvmlite']}; {m['timestamp']}",
             f"Basin map {side}² (early exit; steps/s = needed RK4 steps / wall; × atlas = "
             f"time / the default method's; its labels equal the straightforward kernel's "
             f"(same check interval): {result['map']['labels_equal_straightforward']} "
             f"({result['map']['label_mismatches']} differ); trig-free lanes against theirs: "
             f"{result['map']['trigfree_labels_equal_straightforward']}, against the default's "
             f"{result['map']['trigfree_vs_rk4_label_mismatches']} orbits differ (a different "
             f"discretisation: boundary cells only))"]
    lines += _fmt_rows(result["map"]["rows"], side)
    lines.append("Bulk RK4, fixed steps, no early exit")
    lines += _fmt_rows(result["bulk"]["rows"], side)
    if "torque" in result:
        tq = result["torque"]
        lines.append(f"Torque: the swing equation's {tq['side']}² map (alpha 0.05, omega0 1, "
                     "bSTAB's window, t_max 400 s) against the same points untilted")
        for r in tq["rows"]:
            lines.append(f"  {r['variant']:48s} {_fmt_s(r['wall_s']):>9s} "
                         f"{r['orbits_per_s']:10.3g} orbits/s {r['ratio']:6.2f}× untilted")
    lines.append("Scaling, atlas map")
    for r in result["scaling"]:
        lines.append(f"  {r['n']:5d}² {r['orbits']:9d} orbits {_fmt_s(r['wall_s']):>9s} "
                     f"{r['orbits_per_s']:10.3g} orbits/s {r['ns_per_orbit']:8.1f} ns/orbit")
    if "threads" in result:
        lines.append(f"Threads, atlas map {result['threads']['side']}² (speed-up and "
                     "efficiency against one thread; labels equal one thread's)")
        for r in result["threads"]["rows"]:
            lines.append(f"  {r['threads']:3d} threads {_fmt_s(r['wall_s']):>9s} "
                         f"{r['speedup']:6.2f}× {100 * r['efficiency']:5.0f} %  "
                         f"same labels: {r['same_labels']}")
    lines += _more_lines(result.get("more", {}))
    if "plot" in result:
        pl = result["plot"]
        lines.append(f"Plotting: atlas plot of the default atlas at n² (3 PNGs; maps read band by "
                     f"band, coarsened to ≤ {pl['max_pixels']} px; in process: plot_atlas of the "
                     f"file opened lazily; CLI: the whole command, median, target ≤ "
                     f"{pl['target_cli_512_s']:g} s at 512²; memory of the maps: tracemalloc "
                     f"peak, streamed against whole float64 arrays as before)")
        for r in pl["rows"]:
            lines.append(f"  {r['n']:5d}² {r['orbits']:9d} orbits  in process "
                         f"{_fmt_s(r['plot_s']):>7s}  CLI {_fmt_s(r['cli_s']):>7s}, peak RSS "
                         f"{_fmt_bytes(r['cli_peak_rss_bytes']):>7s}  maps "
                         f"{_fmt_bytes(r['streamed_peak_bytes']):>7s} streamed vs "
                         f"{_fmt_bytes(r['whole_peak_bytes']):>7s} whole "
                         f"({r['image'][0]}² image; atlas run {_fmt_s(r['run_s'])})")
    if "jit" in result:
        for k, j in result["jit"].items():
            lines.append(f"JIT {k:10s}: import {j['import_s']:.2f} s, first call "
                         f"{j['first_call_s']:.2f} s, process {j['process_s']:.2f} s")
    if result.get("quick"):
        lines.append("Quick run (--quick): no trig-free row at equal accuracy, no JIT and no "
                     "end-to-end rows, no in-process plotting time or memory (n/a); `atlas "
                     "bench` runs them")
    t = result["targets"]
    jit = (f"; JIT cold {s['jit_cold_s']:.2f} s (< {t['jit_cold_s']:g}), warm cache "
           f"{s['jit_warm_s']:.2f} s (< {t['jit_warm_s']:g})" if "jit_cold_s" in s else "")
    equal = s.get("trigfree_equal_accuracy")
    equal = (f", {equal['map_speedup']:.2f}× at equal accuracy (dt {equal['dt']:g} s)"
             if equal else "")
    lines.append(f"Summary: default map {s['map_speedup']:.1f}× straightforward (target ≥ "
                 f"{t['map_speedup']:g}×); trig-free map {s['trigfree_map_speedup']:.2f}× the "
                 f"default{equal}; bulk: default "
                 f"{s['default_bulk_msteps_s']:.0f} M steps/s, trig-free "
                 f"{s['bulk_msteps_s']:.0f} (target ≥ {t['bulk_msteps_s']:g}; best of repeats "
                 f"{s['bulk_msteps_s_best']:.0f}), {s['bulk_speedup']:.1f}× straightforward "
                 f"(target ≥ {t['bulk_speedup']:g}×) and {s['bulk_vs_lanes']:.2f}× the default "
                 f"lanes (target ≥ {t['bulk_vs_lanes']:g}×){jit}")
    if "end_to_end" in result:
        from atlas.commands.bench_e2e import format_end_to_end

        lines += format_end_to_end(result["end_to_end"])
    return "\n".join(lines)
