#!/usr/bin/python3
"""Runs the billiards accuracy-versus-cost study and writes docs/billiards-accuracy.md, its plot
(docs/billiards-accuracy.svg) and bench/results/<machine>/billiards_accuracy.csv.

Usage (from the repository root, after a build):
    /usr/bin/python3 bench/billiards_accuracy.py [build/bin/billiards_study]
Needs Debian's python3-matplotlib (scripts/setup installs it).
"""
import csv
import io
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from swing_accuracy import ROOT, machine_name, slug  # noqa: E402


def main():
    study = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "build", "bin", "billiards_study")
    out = subprocess.run([study], check=True, capture_output=True, text=True).stdout
    rows = list(csv.DictReader(io.StringIO(out)))
    machine = machine_name()
    results_dir = os.path.join(ROOT, "bench", "results", slug(machine))
    os.makedirs(results_dir, exist_ok=True)
    with open(os.path.join(results_dir, "billiards_accuracy.csv"), "w") as f:
        f.write(out)

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    scenes = ["straight", "cut", "bank", "bank-drag", "break"]
    fig, axes = plt.subplots(1, len(scenes), figsize=(17, 4), sharey=True)
    styles = {"euler": "s-", "semi_implicit_euler": "^-", "rk4": "D-"}
    for ax, scene in zip(axes, scenes):
        for name, style in styles.items():
            rs = [r for r in rows if r["scene"] == scene and r["integrator"] == name]
            ax.loglog([float(r["cpu_s_per_simulated_s"]) for r in rs],
                      [max(float(r["position_error_m"]), 1e-14) for r in rs], style, label=name)
        ev = [r for r in rows if r["scene"] == scene and r["integrator"] == "event"]
        for r in ev:  # the reference itself: exact, drawn at the floor of the plot
            ax.loglog([float(r["cpu_s_per_simulated_s"])], [1e-14], "k*", markersize=12,
                      label="event (exact)")
        ax.set_title(scene)
        ax.set_xlabel("CPU s per simulated s")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("largest final-position error (m)")
    axes[0].legend()
    fig.suptitle("Billiards engines: error versus cost (%s)" % machine, fontsize=9)
    fig.tight_layout()
    fig.savefig(os.path.join(ROOT, "docs", "billiards-accuracy.svg"))

    tables = []
    for scene in scenes:
        rs = [r for r in rows if r["scene"] == scene]
        tables.append("### %s (reference self-check %s m; %s collision events)\n" % (
            scene, rs[0]["reference_self_error_m"], rs[0]["events_reference"]))
        tables.append("| integrator | dt (s) | final-position error (m) | event-time error (s) "
                      "| events matching | CPU s per simulated s |")
        tables.append("|---|---:|---:|---:|---:|---:|")
        for r in rs:
            if r["integrator"] == "event":
                tables.append("| **event engine** (reference) | exact | 0 | 0 | %s/%s | %.2e |" % (
                    r["events_matched"], r["events_reference"],
                    float(r["cpu_s_per_simulated_s"])))
                continue
            tables.append("| %s | 1/%.0f | %.2e | %.2e | %s/%s | %.2e |" % (
                r["integrator"], 1 / float(r["dt_s"]), float(r["position_error_m"]),
                float(r["event_time_error_s"]), r["events_matched"], r["events_reference"],
                float(r["cpu_s_per_simulated_s"])))
        tables.append("")
    with open(os.path.join(ROOT, "bench", "billiards-accuracy.md.in")) as f:
        text = f.read()
    text = text.replace("@MACHINE@", machine).replace("@TABLES@", "\n".join(tables))
    with open(os.path.join(ROOT, "docs", "billiards-accuracy.md"), "w") as f:
        f.write(text)
    print("wrote docs/billiards-accuracy.md, docs/billiards-accuracy.svg, %s"
          % os.path.relpath(results_dir, ROOT))


if __name__ == "__main__":
    main()
