#!/usr/bin/python3
"""Charts for `mltfarm eval` output (run with Debian's /usr/bin/python3 and python3-matplotlib).

usage: /usr/bin/python3 tools/eval/charts.py DIR

Reads DIR/runs.csv, DIR/acceptance.csv and DIR/refs.csv (written by the harness) and writes, per scene:
  error_time_<scene>.png   relMSE against wall time, log-log: the mean over runs per method and budget,
                           a band of +-1 standard deviation across runs, the reference's noise floor
  spread_<scene>.png       run-to-run spread (stability): every run's relMSE divided by the median of its
                           (method, budget) group; flagged runs (outlier/stuck/brightness) in red
  acceptance_<scene>.png   acceptance rate per path length per Markov chain method (all runs summed)
File names are shared with tools/eval/report.cpp.
"""
import csv
import math
import os
import re
import sys
from collections import OrderedDict, defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def safe_name(s):
    return re.sub(r"[^A-Za-z0-9_.-]", "_", s)


def read_csv(path):
    if not os.path.exists(path):
        return []
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def mean_std(values):
    n = len(values)
    m = sum(values) / n
    s = math.sqrt(sum((v - m) ** 2 for v in values) / (n - 1)) if n > 1 else 0.0
    return m, s


def budget_label(runs):
    budgets = sorted({float(r["budget"]) for r in runs})
    return ", ".join("%g" % b for b in budgets)


def error_time_chart(out, scene, runs, ref):
    groups = OrderedDict()
    for r in runs:
        groups.setdefault(r["method"], defaultdict(list))[int(r["budget_index"])].append(r)
    fig, ax = plt.subplots(figsize=(6.4, 4.4), dpi=110)
    for method, by_budget in groups.items():
        xs, ys, lo, hi = [], [], [], []
        for bi in sorted(by_budget):
            g = by_budget[bi]
            t, _ = mean_std([float(r["seconds"]) for r in g])
            m, s = mean_std([float(r["relMSE"]) for r in g])
            if not (m > 0 and math.isfinite(m)):
                continue
            xs.append(t)
            ys.append(m)
            lo.append(max(m - s, m * 1e-2))
            hi.append(m + s)
        if not xs:
            continue
        line, = ax.plot(xs, ys, marker="o", label=method)
        ax.fill_between(xs, lo, hi, color=line.get_color(), alpha=0.18, linewidth=0)
    if ref and float(ref["relMSE_floor"]) > 0:
        ax.axhline(float(ref["relMSE_floor"]), color="gray", linestyle="--", linewidth=1,
                   label="reference noise floor")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("wall time per run [s]")
    ax.set_ylabel("relMSE (mean over runs, band = +-1 std)")
    mode = runs[0]["mode"]
    ax.set_title("%s: error vs time (budgets %s; %s)" % (scene, budget_label(runs), mode), fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "error_time_%s.png" % safe_name(scene)))
    plt.close(fig)


def spread_chart(out, scene, runs):
    methods = list(OrderedDict.fromkeys(r["method"] for r in runs))
    budgets = sorted({int(r["budget_index"]) for r in runs})
    groups = defaultdict(list)
    for r in runs:
        groups[(r["method"], int(r["budget_index"]))].append(r)
    fig, ax = plt.subplots(figsize=(max(5.0, 1.1 * len(methods) + 2), 4.2), dpi=110)
    cmap = plt.get_cmap("viridis")
    for mi, method in enumerate(methods):
        for bj, bi in enumerate(budgets):
            g = groups.get((method, bi), [])
            errs = sorted(float(r["relMSE"]) for r in g)
            if not errs:
                continue
            med = errs[len(errs) // 2] if len(errs) % 2 else 0.5 * (errs[len(errs) // 2 - 1] + errs[len(errs) // 2])
            for k, r in enumerate(g):
                e = float(r["relMSE"])
                if not (med > 0 and e > 0 and math.isfinite(e)):
                    continue
                x = mi + (bj - (len(budgets) - 1) / 2) * 0.6 / max(1, len(budgets)) + (k - len(g) / 2) * 0.01
                flagged = bool(r["flags"])
                ax.scatter([x], [e / med], s=28 if flagged else 14, marker="x" if flagged else "o",
                           color="red" if flagged else cmap(bj / max(1, len(budgets) - 1)), zorder=3)
    ax.axhline(1.0, color="gray", linewidth=0.8)
    budget_values = {int(r["budget_index"]): float(r["budget"]) for r in runs}
    for bj, bi in enumerate(budgets):
        ax.scatter([], [], s=14, color=cmap(bj / max(1, len(budgets) - 1)), label="budget %g" % budget_values[bi])
    ax.scatter([], [], s=28, marker="x", color="red", label="flagged run")
    ax.legend(fontsize=7, loc="best")
    ax.set_yscale("log")
    ax.set_xticks(range(len(methods)))
    ax.set_xticklabels(methods, rotation=20)
    ax.set_ylabel("relMSE / median of its group")
    ax.set_title("%s: run-to-run spread (colour = budget %s; red x = flagged)" % (scene, budget_label(runs)),
                 fontsize=9)
    ax.grid(True, axis="y", which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "spread_%s.png" % safe_name(scene)))
    plt.close(fig)


def acceptance_chart(out, scene, rows):
    per = OrderedDict()
    for r in rows:
        d = per.setdefault(r["method"], defaultdict(lambda: [0, 0]))
        k = int(r["path_length"])
        d[k][0] += int(r["proposed"])
        d[k][1] += int(r["accepted"])
    fig, ax = plt.subplots(figsize=(6.0, 4.0), dpi=110)
    rates = [d[k][1] / d[k][0] for d in per.values() for k in d if d[k][0] > 0]
    positive = [r for r in rates if r > 0]
    floor = min(positive) / 3 if positive else 1e-4  # where a rate of exactly 0 is drawn
    zero_label = "acceptance 0 (no move accepted)"
    for method, d in per.items():
        ks = sorted(k for k in d if d[k][0] > 0)
        ys = [d[k][1] / d[k][0] for k in ks]
        line, = ax.plot(ks, [max(y, floor) for y in ys], marker="o", label=method)
        zeros = [k for k, y in zip(ks, ys) if y == 0]
        if zeros:
            ax.scatter(zeros, [floor] * len(zeros), marker="v", s=60, color="red", zorder=4, label=zero_label)
            zero_label = None
    ax.set_yscale("log")
    ax.set_xlabel("path length k (segments; pssmlt: 0 = all lengths)")
    ax.set_ylabel("acceptance rate (all runs)")
    ax.set_title("%s: acceptance per path length" % scene, fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "acceptance_%s.png" % safe_name(scene)))
    plt.close(fig)


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    out = sys.argv[1]
    runs = read_csv(os.path.join(out, "runs.csv"))
    if not runs:
        sys.exit("charts.py: %s has no runs" % os.path.join(out, "runs.csv"))
    acc = read_csv(os.path.join(out, "acceptance.csv"))
    refs = {r["scene"]: r for r in read_csv(os.path.join(out, "refs.csv"))}
    for scene in OrderedDict.fromkeys(r["scene"] for r in runs):
        scene_runs = [r for r in runs if r["scene"] == scene]
        error_time_chart(out, scene, scene_runs, refs.get(scene))
        spread_chart(out, scene, scene_runs)
        scene_acc = [r for r in acc if r["scene"] == scene]
        if scene_acc:
            acceptance_chart(out, scene, scene_acc)


if __name__ == "__main__":
    main()
