"""The benchmarks page's tables and plots, drawn from docs/benchmarks/results.json at every build.

The numbers live in that file only (one object per benchmark script, one entry per recorded run);
docs/benchmarks.md includes the tables and shows the figures this module writes:
``tables/<name>.md`` and ``figures/<name>.png`` under the output folder (both not committed).
"""

from __future__ import annotations

import json
from pathlib import Path


def _table(header: list[str], rows: list[list[object]]) -> str:
    def cell(value: object) -> str:
        return "" if value is None else str(value).replace("|", "\\|")

    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(cell(value) for value in row) + " |" for row in rows]
    return "\n".join(lines) + "\n"


def _seconds(value: float | None) -> str | None:
    return None if value is None else f"{value:.2f} s"


def tables(results: dict) -> dict[str, str]:
    """Markdown tables of every benchmark, by name."""
    core = results["core"]
    agreement = core["agreement"]
    core_rows = [[agreement["what"], f"max final-state difference {agreement['max_final_state_difference']:.1e}",
                  f"within {agreement['tolerance']:.0e}", None]]
    for row in core["speed"]:
        core_rows.append([row["what"], f"{row['measured']:.1e} {row['unit']}", f"{row['reference']:.1e} {row['unit']}",
                          f"{row['ratio']:.1f}x (target {row['target_ratio']}x)"])
    for row in core["other"]:
        core_rows.append([row["what"], row["measured"], row.get("target"), None])
    targets = [[row["what"], row["measured"], row["target"], f"{row['ratio']:.2f}"]
               for row in results["targets"]["rows"]]
    kiosk = results["kiosk"]
    # The summary is the newest run timed in the page that measured every server and the memory.
    summary = [run for run in kiosk["runs"] if run.get("timed") == "in the page" and "memory_mb" in run][-1]
    memory = summary["memory_mb"]
    kiosk_summary = _table(
        ["demo page", "shipped `deploy/voila/voila.py`", "stock Voila (reference)", "ratio", "shipped, no preheat"],
        [[f"server + kernels memory after {summary['visits']} visits (RSS summed)",
          f"{memory['shipped']:,} MB ({memory['shipped_kernels']})",
          f"{memory['stock']:,} MB ({memory['stock_kernels']} kernels)", f"{memory['shipped'] / memory['stock']:.2f}",
          f"{memory['shipped_no_preheat']} MB"],
         ["time to interactive, warm, p50 / p95", f"{summary['shipped_p50']:.2f} s / {summary['shipped_p95']:.2f} s",
          f"{summary['stock_p50']:.2f} s / {summary['stock_p95']:.2f} s",
          f"{summary['shipped_p50'] / summary['stock_p50']:.2f}",
          f"{summary['shipped_no_preheat_p50']:.2f} s / {summary['shipped_no_preheat_p95']:.2f} s"]])
    kiosk_runs = _table(["date", "run", "times", "shipped p50", "shipped p95", "stock p50", "stock p95", "ratio (p50)"],
                        [[run["date"], run["label"], run.get("timed", "polled"), _seconds(run["shipped_p50"]),
                          _seconds(run.get("shipped_p95")), _seconds(run["stock_p50"]), _seconds(run.get("stock_p95")),
                          f"{run['shipped_p50'] / run['stock_p50']:.2f}"] for run in kiosk["runs"]])
    online = _table(["participants at once", "arrival (navigation -> welcome), p50 / max",
                     "response (click -> next screen), p50 / p95 / max", "server + kernels memory", "per kernel"],
                    [[run["participants"], f"{run['arrival_p50_s']} s / {run['arrival_max_s']} s",
                      f"{run['response_p50_s']:.2f} s / {run['response_p95_s']:.2f} s / {run['response_max_s']:.2f} s",
                      f"{run['memory_mb']:,} MB ({run['kernels']} kernels)", f"{run['per_kernel_mb']} MB"]
                     for run in results["online"]["runs"]])
    hub = results["hub"]
    hub_rows = []
    for run in hub["runs"]:
        hub_rows.append([run["label"], _seconds(run.get("all_ready_s")), _seconds(run.get("first_episode_alone_s")),
                         None if "feedback_p95_ms" not in run else
                         f"{run.get('feedback_p50_ms', '-')} / {run['feedback_p95_ms']} ms",
                         None if "feedback_all_p95_ms" not in run else
                         f"{run['feedback_all_p50_ms']} / {run['feedback_all_p95_ms']} ms",
                         f"{run['pss_mib']} ({run['pss_server_mib']} + {run['pss_kernel_mib']})",
                         run.get("rss_mib"), run.get("uss_mib"), run.get("students_per_core")])
    hub_table = _table(["run (thirty students)", "all ready", "first episode, alone",
                        "feedback p50 / p95, human pace", "feedback p50 / p95, all at once",
                        "PSS MiB a student (server + kernel)", "RSS MiB", "USS MiB", "students per core"], hub_rows)
    before = hub["before"]
    target = hub["targets"]
    hub_before = _table(["what (thirty students)", "before (issue, idle)", "target (idle)"],
                        [["spawn, all started together", before["spawn"],
                          f"thirty within {target['spawn_all_ready_s']} s"],
                         ["first episode, fresh kernel, imports included",
                          f"three episodes: {before['first_episode_s']} s", f"{target['first_episode_s']} s"],
                         ["feedback, human pace (an arrow every 3-8 s)", "not measured",
                          f"p95 <= {target['feedback_p95_ms']} ms"],
                         ["feedback, all at once", before["feedback_all_at_once"], "reported"],
                         ["memory per student (server + kernel after its episodes)",
                          f"{before['memory_per_student_mib']} MiB", f"<= {target['pss_per_student_mib']} MiB"]])
    return {"core": _table(["what", "mt-widgets", "reference", "ratio"], core_rows),
            "targets": _table(["what", "measured", "target", "ratio"], targets),
            "kiosk": kiosk_summary, "kiosk_runs": kiosk_runs, "online": online, "hub": hub_table,
            "hub_before": hub_before}


def figures(results: dict, folder: Path) -> list[Path]:
    """The plots, as PNG files in ``folder``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    written = []

    def save(figure, name):
        figure.tight_layout()
        path = folder / f"{name}.png"
        figure.savefig(path, dpi=110)
        plt.close(figure)
        written.append(path)

    # Targets: every measured figure over its target.
    rows = results["targets"]["rows"]
    figure, axes = plt.subplots(figsize=(8, 3.6))
    labels = [row["what"].split(",")[0].split(" (")[0] for row in rows]
    colours = ["#0072B2" if row["kind"] == "ceiling" else "#009E73" for row in rows]
    axes.barh(labels, [row["ratio"] for row in rows], color=colours)
    axes.axvline(1.0, color="black", linestyle="--", linewidth=1)
    axes.invert_yaxis()
    axes.set_xlabel("measured / target (blue: a ceiling, below 1 meets it; green: a floor, above 1 meets it)")
    axes.tick_params(axis="y", labelsize=8)
    save(figure, "targets")

    # The core against MuJoCo: speed-up and its target.
    speed = results["core"]["speed"]
    figure, axes = plt.subplots(figsize=(6, 2.6))
    names = [row["what"].split(" vs ")[0].replace("`", "") for row in speed]
    axes.barh(names, [row["ratio"] for row in speed], color="#0072B2", label="measured")
    axes.scatter([row["target_ratio"] for row in speed], names, marker="|", s=400, color="#D55E00", label="target",
                 zorder=3)
    axes.invert_yaxis()
    axes.set_xlabel("speed-up over MuJoCo (x)")
    axes.legend(loc="lower right", fontsize=8)
    axes.tick_params(axis="y", labelsize=8)
    save(figure, "core")

    # The kiosk, run by run.
    kiosk = results["kiosk"]
    runs = kiosk["runs"]
    figure, axes = plt.subplots(figsize=(8, 3.8))
    positions = range(len(runs))
    axes.plot(positions, [run["stock_p50"] for run in runs], "s--", color="#999999", label="stock Voila p50")
    axes.plot(positions, [run["shipped_p50"] for run in runs], "o-", color="#0072B2", label="shipped p50")
    axes.plot(positions, [run.get("shipped_p95", float("nan")) for run in runs], "v", color="#56B4E9",
              label="shipped p95")
    axes.axhline(kiosk["target_p50_s"], color="#D55E00", linestyle=":", label="target p50")
    in_page = [index for index, run in enumerate(runs) if run.get("timed") == "in the page"]
    if in_page:  # before this line Playwright polled for the canvas: every time is late by up to 0.5 s
        axes.axvline(in_page[0] - 0.5, color="black", linewidth=0.8)
        axes.text(in_page[0] - 0.4, 0.05, "timed in the page", fontsize=7, transform=axes.get_xaxis_transform())
    axes.set_xticks(list(positions), [f"{run['date'][5:]}\n#{index + 1}" for index, run in enumerate(runs)], fontsize=7)
    axes.set_ylabel("time to interactive (s)")
    axes.set_ylim(0, None)
    axes.legend(fontsize=8, ncol=2)
    save(figure, "kiosk")

    # The online study: memory grows with the open pages.
    online = results["online"]["runs"]
    figure, axes = plt.subplots(figsize=(5, 3))
    axes.plot([run["participants"] for run in online], [run["memory_mb"] for run in online], "o-", color="#0072B2")
    axes.set_xlabel("participants at once")
    axes.set_ylabel("server + kernels (MB)")
    axes.set_ylim(0, None)
    save(figure, "online")

    # The class hub: memory per student, run by run, and its target.
    hub = results["hub"]
    figure, axes = plt.subplots(figsize=(7, 3))
    labels = ["before"] + [f"run {index + 1}" for index in range(len(hub["runs"]))]
    axes.bar(labels[:1], [hub["before"]["memory_per_student_mib"]], color="#999999")
    axes.bar(labels[1:], [run["pss_server_mib"] for run in hub["runs"]], color="#0072B2", label="server (PSS)")
    axes.bar(labels[1:], [run["pss_kernel_mib"] for run in hub["runs"]],
             bottom=[run["pss_server_mib"] for run in hub["runs"]], color="#56B4E9", label="kernel (PSS)")
    axes.axhline(hub["targets"]["pss_per_student_mib"], color="#D55E00", linestyle=":", label="target")
    axes.set_ylabel("MiB per student")
    axes.legend(fontsize=8)
    save(figure, "hub")
    return written


def plot_all(source: Path, output: Path) -> None:
    """Reads ``source``/results.json, writes ``output``/tables/*.md and ``output``/figures/*.png."""
    results = json.loads((source / "results.json").read_text())
    (output / "tables").mkdir(parents=True, exist_ok=True)
    (output / "figures").mkdir(parents=True, exist_ok=True)
    for name, text in tables(results).items():
        (output / "tables" / f"{name}.md").write_text(text)
    figures(results, output / "figures")
