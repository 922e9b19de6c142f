#!/usr/bin/python3
"""Runs the swing accuracy-versus-cost study and writes docs/swing-accuracy.md, its plot
(docs/swing-accuracy.svg) and bench/results/<machine>/swing_accuracy.csv.

Usage (from the repository root, after a build):  bench/swing_accuracy.py [build/bin/swing_study]
Needs Debian's python3-matplotlib (scripts/setup installs it); run with /usr/bin/python3.
"""
import csv
import io
import os
import platform
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def machine_name():
    model = "unknown cpu"
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    model = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return "%s, %d cores" % (model, os.cpu_count() or 0)


def slug(text):
    return re.sub(r"[^a-z0-9]+", "-", text.lower()).strip("-")[:60]


def main():
    study = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "build", "bin", "swing_study")
    out = subprocess.run([study], check=True, capture_output=True, text=True).stdout
    header = out.splitlines()[0]
    ref = dict(kv.split("=") for kv in header[2:].split()[2:])
    rows = list(csv.DictReader(io.StringIO("\n".join(out.splitlines()[1:]))))
    machine = machine_name()

    results_dir = os.path.join(ROOT, "bench", "results", slug(machine))
    os.makedirs(results_dir, exist_ok=True)
    with open(os.path.join(results_dir, "swing_accuracy.csv"), "w") as f:
        f.write(out)

    # The plot: |impact-time error| and |speed error| against CPU time per swing.
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
    styles = {"book": "o-", "euler": "s-", "semi_implicit_euler": "^-", "rk4": "D-", "dp45": "v-"}
    for name, style in styles.items():
        ok = [r for r in rows if r["integrator"] == name and r["status"] == "ok"]
        cpu = [float(r["cpu_us_median"]) for r in ok]
        for ax, key in zip(axes, ("t_err_s", "speed_err_mps")):
            ax.loglog(cpu, [max(abs(float(r[key])), 1e-16) for r in ok], style, label=name)
    axes[0].set_ylabel("|impact time error| (s)")
    axes[1].set_ylabel("|impact clubhead speed error| (m/s)")
    for ax in axes:
        ax.set_xlabel("CPU time per swing (us, median)")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend()
    fig.suptitle("Chapter swing to impact: error versus cost (%s)" % machine, fontsize=9)
    fig.tight_layout()
    fig.savefig(os.path.join(ROOT, "docs", "swing-accuracy.svg"))

    def row(name, setting):
        for r in rows:
            if r["integrator"] == name and float(r["setting"]) == setting:
                return r
        raise KeyError((name, setting))

    table = ["| integrator | dt (s) or tolerance | steps | force evals | impact time error (s) "
             "| speed error (m/s) | max angle error (rad) | CPU per swing (us) |",
             "|---|---|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        if r["status"] != "ok":
            table.append("| %s | %s | | | rejected: %s | | | |" % (
                r["integrator"], r["setting"], r["status"].split(":")[0] + " (turn bound)"))
            continue
        table.append("| %s | %s | %s | %s | %.2e | %.2e | %.2e | %.1f |" % (
            r["integrator"], r["setting"], r["steps"], r["rhs_evaluations"], float(r["t_err_s"]),
            float(r["speed_err_mps"]), float(r["max_angle_err_rad"]), float(r["cpu_us_median"])))

    book, rk4 = row("book", 0.0025), row("rk4", 0.0025)
    values = {
        "MACHINE": machine,
        "REF_T": "%.12f" % float(ref["t_s"]),
        "REF_V": "%.10f" % float(ref["speed_mps"]),
        "REF_VG": "%.10f" % float(ref["ground_speed_mps"]),
        "RK4_CHECK_T": "%.1e" % abs(float(ref["rk4_1e-5_dt_diff_s"])),
        "RK4_CHECK_V": "%.1e" % abs(float(ref["rk4_1e-5_dv_diff_mps"])),
        "TABLE": "\n".join(table),
        "BOOK_CPU": "%.0f" % float(book["cpu_us_median"]),
        "BOOK_T": "%.1e" % abs(float(book["t_err_s"])),
        "BOOK_V": "%.2f" % abs(float(book["speed_err_mps"])),
        "RK4_CPU": "%.0f" % float(rk4["cpu_us_median"]),
        "RK4_T": "%.1e" % abs(float(rk4["t_err_s"])),
        "RK4_V": "%.1e" % abs(float(rk4["speed_err_mps"])),
        "BOOK_FINE_CPU": "%.0f" % float(row("book", 0.0001)["cpu_us_median"]),
        "BOOK_FINE_T": "%.1e" % abs(float(row("book", 0.0001)["t_err_s"])),
        "RK4_COARSE_CPU": "%.0f" % float(row("rk4", 0.01)["cpu_us_median"]),
        "RK4_COARSE_T": "%.1e" % abs(float(row("rk4", 0.01)["t_err_s"])),
        "DP45_CPU": "%.0f" % float(row("dp45", 1e-8)["cpu_us_median"]),
        "DP45_T": "%.1e" % abs(float(row("dp45", 1e-8)["t_err_s"])),
    }
    with open(os.path.join(ROOT, "bench", "swing-accuracy.md.in")) as f:
        text = f.read()
    for k, v in values.items():
        text = text.replace("@%s@" % k, v)
    with open(os.path.join(ROOT, "docs", "swing-accuracy.md"), "w") as f:
        f.write(text)
    print("wrote docs/swing-accuracy.md, docs/swing-accuracy.svg, %s" % os.path.relpath(results_dir, ROOT))


if __name__ == "__main__":
    main()
