#!/usr/bin/python3
"""Combines several `mltfarm eval` output directories into one results page (issue 9 item 6).

usage: /usr/bin/python3 tools/eval/results_page.py --out DIR --page PAGE.md [--header FILE] [--keep OLDDIR] EVALDIR...

Each EVALDIR holds what one `mltfarm eval` call wrote (runs.csv, acceptance.csv, refs.csv,
calibration.csv, kinds.csv, bands.csv). Different calls may cover different methods or budgets of the same scene (e.g. every
method at 4 and 16 s, the leading methods at 64 s); their rows are pooled, budget indices are renumbered
by budget value, DIR gets the pooled tables and the charts (tools/eval/charts.py), and PAGE.md gets, per
scene, the reference's own noise, relMSE per method and budget, brightness per run, throughput, bootstrap
share, acceptance per mutation kind (where kinds.csv has them) and stability flags, followed by a check of issue 9's targets. Nothing here measures anything: it
only reads the tables.
"""
import argparse
import csv
import os
import shutil
import statistics
import subprocess
import sys
from collections import OrderedDict, defaultdict

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from charts import mean_std  # noqa: E402  (the charts' mean and sample standard deviation)

HARD_SCENES = ("caustic-mirror", "door-ajar", "glossy-plates")
TIME_OFF = 0.05  # a point whose mean run time is further than this from its budget shows that time
CHAIN_METHODS = ("pssmlt", "pssmlt-bdpt", "mmlt", "rjmlt", "veach-mlt")


METHOD_ORDER = ("pt", "lt", "bdpt") + CHAIN_METHODS


def method_rank(label):  # known methods in METHOD_ORDER, a METHOD+variant after its method, others last
    base = label.split("+")[0]
    return (METHOD_ORDER.index(base) if base in METHOD_ORDER else len(METHOD_ORDER), label != base)


def is_chain(label):  # a method label, also METHOD+separate-direct (the harness's method spec)
    return label.split("+")[0] in CHAIN_METHODS


def read_csv(path):
    if not os.path.exists(path):
        return [], None
    with open(path, newline="") as f:
        r = csv.DictReader(f)
        return list(r), r.fieldnames


def write_csv(path, rows, fields):
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields, lineterminator="\n")
        w.writeheader()
        w.writerows(rows)


def fmt_e(x):
    return "%.2e" % x if x < 0.01 or x >= 100 else "%.3g" % x


def pct(x):
    return "%+.2f%%" % (100 * x)


def pool(dirs, out, keep=None):
    """Pools the tables of every eval directory into out/; returns (runs, refs, acceptance).

    keep: a directory of pooled tables (a previous page's docs/results) whose rows are kept for every
    (scene, method, budget) that no eval directory has: a page with a few scenes rerun, or a budget added to
    one, and the rest as it was. A scene's reference comes from the eval directories when they have one."""
    runs, acc, refs, cal, kinds, bands = [], [], OrderedDict(), [], [], []
    fields = {}
    eval_runs = {}  # each eval directory's runs.csv, read once
    for d in dirs:
        eval_runs[d] = read_csv(os.path.join(d, "runs.csv"))
        if not eval_runs[d][0]:
            sys.exit("results_page.py: %s has no runs" % os.path.join(d, "runs.csv"))

    def run_key(x):
        return (x["scene"], x["method"], float(x["budget"]))
    fresh = {run_key(x) for r, _ in eval_runs.values() for x in r}  # rows the kept tables give up
    fresh_methods = {k[:2] for k in fresh}  # calibration.csv is per (scene, method)
    sources = [(d, False) for d in dirs] + ([(keep, True)] if keep else [])
    for d, only_kept in sources:
        def kept(rows, key=run_key, rerun=fresh):  # a kept directory's rows that were not rerun
            return [x for x in rows if key(x) not in rerun] if only_kept else rows

        r, f = eval_runs[d] if d in eval_runs else read_csv(os.path.join(d, "runs.csv"))
        if only_kept and not r:
            sys.exit("results_page.py: --keep %s has no runs.csv" % d)
        r = kept(r)
        # The union of the columns, in order: eval outputs written before a column was added lack it.
        fields["runs"] = fields.get("runs", []) + [c for c in f if c not in fields.get("runs", [])]
        runs += r
        a, f = read_csv(os.path.join(d, "acceptance.csv"))
        a = kept(a)
        if f:
            fields["acc"] = f
        acc += a
        k, f = read_csv(os.path.join(d, "kinds.csv"))  # per mutation kind; older eval outputs have none
        k = kept(k)
        if f:
            fields["kinds"] = f
        kinds += k
        bb, f = read_csv(os.path.join(d, "bands.csv"))  # per run and brightness band; older outputs have none
        bb = kept(bb)
        if f:
            fields["bands"] = f
        bands += bb
        rr, f = read_csv(os.path.join(d, "refs.csv"))
        fields["refs"] = f
        for x in rr:  # the eval directories' references come first and win
            refs.setdefault(x["scene"], x)
        c, f = read_csv(os.path.join(d, "calibration.csv"))
        c = kept(c, key=lambda x: (x["scene"], x["method"]), rerun=fresh_methods)
        if f:
            fields["cal"] = f
        cal += c
    budgets = sorted({float(r["budget"]) for r in runs})
    index = {b: i for i, b in enumerate(budgets)}
    for rows in (runs, acc, kinds):
        for r in rows:
            r["budget_index"] = str(index[float(r["budget"])])
    os.makedirs(out, exist_ok=True)
    write_csv(os.path.join(out, "runs.csv"), runs, fields["runs"])
    if "acc" in fields:
        write_csv(os.path.join(out, "acceptance.csv"), acc, fields["acc"])
    write_csv(os.path.join(out, "refs.csv"), list(refs.values()), fields["refs"])
    if "cal" in fields:
        write_csv(os.path.join(out, "calibration.csv"), cal, fields["cal"])
    if "kinds" in fields:
        write_csv(os.path.join(out, "kinds.csv"), kinds, fields["kinds"])
    if "bands" in fields:
        write_csv(os.path.join(out, "bands.csv"), bands, fields["bands"])
    return runs, refs, budgets, kinds, bands


class Group:
    """The runs of one (scene, method, budget)."""

    def __init__(self, rows):
        self.rows = rows
        self.rel = [float(r["relMSE"]) for r in rows]
        self.mean_err = [float(r["meanErr"]) for r in rows]
        self.seconds = [float(r["seconds"]) for r in rows]
        self.work = [float(r["work"]) for r in rows]
        self.samples = [float(r["samples"]) for r in rows]
        plan = [float(r["plan_seconds"]) for r in rows if r.get("plan_seconds")]
        self.plan_share = [p / s for p, s in zip(plan, self.seconds)] if plan else []
        self.flagged = [r for r in rows if r["flags"]]
        # An ideal luminance-target chain's relMSE at each run's mutations (runs.csv ideal_relMSE; eval outputs
        # written before it lack it): the mean relMSE over its mean, where every run has one.
        ideal = [float(r["ideal_relMSE"]) for r in rows if r.get("ideal_relMSE")]
        self.over_ideal = sum(self.rel) / sum(ideal) if ideal and len(ideal) == len(rows) else None

    def rel_ms(self):
        return mean_std(self.rel)

    def mean_seconds(self):  # wall time of a run, bootstrap included
        return sum(self.seconds) / len(self.seconds)

    def throughput(self):  # samples or mutations per second of wall time (bootstrap included)
        return sum(self.samples) / sum(self.seconds)


def kinds_lines(kinds, bd):
    """Acceptance per mutation kind at budget bd, per method: accepted / proposed over all runs, and the
    share of the proposals each kind had (rjmlt's technique changes, veach-mlt's five mutations, ...)."""
    per = OrderedDict()
    for r in kinds:
        if float(r["budget"]) != bd:
            continue
        m = per.setdefault(r["method"], OrderedDict())
        p, a = m.get(r["kind"], (0, 0))
        m[r["kind"]] = (p + int(r["proposed"]), a + int(r["accepted"]))
    if not per:
        return []
    lines = ["Acceptance per mutation kind at %g s (accepted / proposed over the runs; in brackets the kind's "
             "share of the proposals):" % bd, "", "| method | acceptance per kind |", "|---|---|"]
    for m, ks in per.items():
        total = sum(p for p, _ in ks.values()) or 1
        lines.append("| %s | %s |" % (m, ", ".join(
            "%s %.3f (%.0f%%)" % (k, a / p if p else 0.0, 100.0 * p / total) for k, (p, a) in ks.items() if p > 0)))
    return lines + [""]


def bands_lines(bands, bd, methods):
    """The error split by the reference's brightness at budget bd (bands.csv, tools/eval/bands.h): per method
    the mean over runs of each band's relMSE, its share of the method's error and, for chains whose every run
    has it, the band over the ideal chain's band. Methods without bands.csv rows are left out."""
    per = OrderedDict()  # method -> band -> [(rel, ideal or None)]
    for r in bands:
        if float(r["budget"]) != bd:
            continue
        per.setdefault(r["method"], OrderedDict()).setdefault(r["band"], []).append(
            (float(r["rel_mse"]), float(r["ideal_rel_mse"]) if r["ideal_rel_mse"] else None))
    shown = [m for m in methods if m in per]
    if not shown:
        return []
    names = list(per[shown[0]].keys())
    lines = ["Where the error is at %g s: the mean relMSE split by the reference's brightness (pixels ranked by "
             "its luminance; the bands add up to the relMSE), each band's share, and for chains the band over "
             "an ideal chain's (docs/CHAINS.md, \"Where the error is, in the harness\"):" % bd, "",
             "| method | " + " | ".join(names) + " |", "|---|" + "---|" * len(names)]
    for m in shown:
        means = [mean_std([v for v, _ in per[m].get(n, [])])[0] if per[m].get(n) else 0.0 for n in names]
        total = sum(means) or 1.0
        cells = []
        for n, mu in zip(names, means):
            ideals = [i for _, i in per[m].get(n, [])]
            over = ""
            if ideals and all(i is not None and i > 0 for i in ideals):
                over = ", %.2gx" % (mu / mean_std(ideals)[0])
            cells.append("%s (%.0f%%%s)" % (fmt_e(mu), 100 * mu / total, over))
        lines.append("| %s | %s |" % (m, " | ".join(cells)))
    return lines + [""]


def scene_section(scene, runs, ref, budgets, out_rel, kinds=(), bands=()):
    lines = ["## %s" % scene, ""]
    groups = OrderedDict()
    for r in runs:
        groups.setdefault(r["method"], OrderedDict())
    by = defaultdict(list)
    for r in runs:
        by[(r["method"], float(r["budget"]))].append(r)
    g = {k: Group(v) for k, v in by.items()}
    methods = sorted(groups, key=method_rank)  # the same order on every scene, whatever order the runs came in
    if ref:
        lines.append("Reference: %s; its own noise: relMSE floor %s, mean brightness +-%.3f%% (1 std. error)."
                     % (ref["source"], fmt_e(float(ref["relMSE_floor"])), 100 * float(ref["mean_rel_stderr"])))
        lines.append("")
    lines.append("![relMSE against time, %s](%s/error_time_%s.png)" % (scene, out_rel, scene))
    lines.append("")
    lines.append("relMSE, mean +- std over runs (runs); lower is better; **bold** = best at that budget. Where a "
                 "point's runs took on average more than %d%% more or less than its budget (the host's speed "
                 "drifting under the harness's time model), the mean time follows the count: at equal time a "
                 "method that ran longer is flattered." % round(100 * TIME_OFF))
    lines.append("")
    lines.append("| method | " + " | ".join("%g s" % b for b in budgets) + " |")
    lines.append("|---|" + "---|" * len(budgets))
    best = {}
    for b in budgets:
        cand = [(g[(m, b)].rel_ms()[0], m) for m in methods if (m, b) in g]
        if cand:
            best[b] = min(cand)[1]
    for m in methods:
        cells = []
        for b in budgets:
            if (m, b) not in g:
                cells.append("-")
                continue
            mu, sd = g[(m, b)].rel_ms()
            t = g[(m, b)].mean_seconds()
            took = ", %.1f s" % t if abs(t / b - 1) > TIME_OFF else ""
            cell = "%s +- %s (%d%s)" % (fmt_e(mu), fmt_e(sd), len(g[(m, b)].rel), took)
            cells.append("**%s**" % cell if best.get(b) == m else cell)
        lines.append("| %s | %s |" % (m, " | ".join(cells)))
    lines.append("")
    # Detail at 16 s (or the closest budget every method ran).
    common = [b for b in budgets if all((m, b) in g for m in methods)]
    bd = 16.0 if 16.0 in common else (common[-1] if common else budgets[0])
    lines.append("At %g s: brightness (image mean's relative error against the reference) per run, work, "
                 "throughput (wall time incl. bootstrap), bootstrap share of the job, the chains' relMSE over an "
                 "ideal chain's at their mutations (docs/CHAINS.md, \"How far the chains are from an ideal "
                 "chain\"), flagged runs." % bd)
    lines.append("")
    lines.append("| method | brightness mean over runs | worst run | per run | work/px | samples or mutations/s "
                 "| bootstrap share | over ideal | flagged |")
    lines.append("|---|---|---|---|---|---|---|---|---|")
    for m in methods:
        if (m, bd) not in g:
            continue
        x = g[(m, bd)]
        mu, _ = mean_std(x.mean_err)
        worst = max(x.mean_err, key=abs)
        share = "%.1f%%" % (100 * max(x.plan_share)) if x.plan_share and is_chain(m) else "-"
        flags = "; ".join(sorted({f for r in x.flagged for f in r["flags"].split(";")}))
        over = "%.2gx" % x.over_ideal if x.over_ideal is not None else "-"
        lines.append("| %s | %s | %s | %s | %.0f | %.3g M | %s | %s | %d/%d %s |" % (
            m, pct(mu), pct(worst), ", ".join("%+.2f" % (100 * e) for e in x.mean_err), mean_std(x.work)[0],
            x.throughput() / 1e6, share, over, len(x.flagged), len(x.rows), flags))
    lines.append("")
    lines += kinds_lines(kinds, bd)
    lines += bands_lines(bands, bd, methods)
    # Which method to pick: the lowest mean relMSE at the detail budget among methods without flagged runs.
    clean = [(g[(m, bd)].rel_ms()[0], m) for m in methods if (m, bd) in g and not g[(m, bd)].flagged]
    if clean:
        e, m = min(clean)
        lines.append("**Pick here:** `%s` (lowest relMSE at %g s among methods with no flagged run: %s)."
                     % (m, bd, fmt_e(e)))
        lines.append("")
    lines.append("![run-to-run spread, %s](%s/spread_%s.png)" % (scene, out_rel, scene))
    lines.append("")
    return lines, g, methods


def targets_section(all_groups, refs, budgets):
    lines = ["## Issue 9's targets, checked against these runs", ""]
    # 1. Brightness.
    lines.append("**Brightness** (target: mean over seeds within 0.1%, every single run within 0.3% at 16 s). "
                 "The reference's own brightness standard error is part of every figure. Whether a mean that "
                 "misses the target shows a bias or only the runs' spread: its standard error (the standard "
                 "deviation of the seeds' means / sqrt(seeds): the runs of one job seed on the two cores share its "
                 "bootstrap and so most of their brightness error, so they count once) and the median run; "
                 "\"beyond 2 s.e.\" is \"yes\" when the "
                 "mean lies further from 0 than 2 combined standard errors (runs' and reference's). Read it with "
                 "care: over some 50 rows about 2 are \"yes\" by chance alone, and where a few rare paths carry "
                 "much of the light (caustic-mirror's caustic seen in the mirror, reached only by paths that hit "
                 "the light by chance) 10 runs rarely hold one, so the median and most runs fall short of the mean "
                 "and the runs' standard error understates the truth: there a \"yes\" may be the heavy tail, not a bias "
                 "of the estimator.")
    lines.append("")
    lines.append("| scene | method | mean over seeds | its s.e. | median run | worst single run | reference +-1 s.e. "
                 "| beyond 2 s.e.? | met? |")
    lines.append("|---|---|---|---|---|---|---|---|---|")
    for scene, (g, methods) in all_groups.items():
        se = float(refs[scene]["mean_rel_stderr"]) if scene in refs else 0.0
        for m in methods:
            if (m, 16.0) not in g:
                continue
            x = g[(m, 16.0)]
            # Runs of the same job seed (CPUS=a,b runs every seed on both cores) share the bootstrap, hence b's
            # error: the mean and its standard error are over the seeds' means.
            per_seed = OrderedDict()
            for r in x.rows:
                per_seed.setdefault(r["seed"], []).append(float(r["meanErr"]))
            seed_means = [sum(v) / len(v) for v in per_seed.values()]
            mu, sd = mean_std(seed_means)
            n = len(seed_means)
            worst = max(x.mean_err, key=abs)
            ok = abs(mu) <= 0.001 + 2 * se and abs(worst) <= 0.003 + 2 * se
            se_cell, beyond = "-", "-"  # one seed has no spread to judge by
            if n > 1:
                se_mu = sd / n ** 0.5
                se_cell = "%.2f%%" % (100 * se_mu)
                beyond = "yes" if abs(mu) > 2 * (se_mu ** 2 + se ** 2) ** 0.5 else "no"
            lines.append("| %s | %s | %s | %s | %s | %s | %.3f%% | %s | %s |" % (
                scene, m, pct(mu), se_cell, pct(statistics.median(x.mean_err)), pct(worst), 100 * se, beyond,
                "yes" if ok else "no"))
    lines.append("")
    # 2. mmlt vs bdpt on the Cornell box.
    if "cornell-box" in all_groups:
        g, _ = all_groups["cornell-box"]
        lines.append("**Cornell box, mmlt against bdpt** (target: mmlt no worse at 16 s):")
        lines.append("")
        for b in budgets:
            if ("mmlt", b) in g and ("bdpt", b) in g:
                r = g[("mmlt", b)].rel_ms()[0] / g[("bdpt", b)].rel_ms()[0]
                lines.append("- %g s: mmlt / bdpt relMSE = %.2f (%s)" % (b, r, "met" if r <= 1 else "not met"))
        lines.append("")
    # 3. Hard scenes: best chain vs pt and bdpt.
    lines.append("**Hard scenes** (target: the best chain method at least 2x lower relMSE than both pt and "
                 "bdpt at equal time):")
    lines.append("")
    lines.append("| scene | budget | best chain method | its relMSE | pt | bdpt | ratio to the better of pt/bdpt | met? |")
    lines.append("|---|---|---|---|---|---|---|---|")
    for scene in HARD_SCENES:
        if scene not in all_groups:
            continue
        g, methods = all_groups[scene]
        for b in budgets:
            chains = [(g[(m, b)].rel_ms()[0], m) for m in methods if is_chain(m) and (m, b) in g]
            if not chains or ("pt", b) not in g or ("bdpt", b) not in g:
                continue
            e, m = min(chains)
            pt, bd = g[("pt", b)].rel_ms()[0], g[("bdpt", b)].rel_ms()[0]
            ratio = min(pt, bd) / e
            lines.append("| %s | %g s | %s | %s | %s | %s | %.2fx | %s |" % (
                scene, b, m, fmt_e(e), fmt_e(pt), fmt_e(bd), ratio, "yes" if ratio >= 2 else "no"))
    lines.append("")
    # 4. The references' own noise (item 6): at most a tenth of the best method's error. A run's relMSE
    # against a noisy reference is its own error plus the reference's floor (independent noise), so the
    # check compares the floor with the best mean relMSE less the floor.
    lines.append("**References** (target: each reference's own noise floor at most a tenth of the best "
                 "method's error; that error taken as the best mean relMSE at the scene's largest budget "
                 "less the floor, since a run's relMSE against the reference includes it):")
    lines.append("")
    lines.append("| scene | reference | floor | best method, budget | its relMSE | floor / (relMSE - floor) | met? |")
    lines.append("|---|---|---|---|---|---|---|")
    for scene, (g, methods) in all_groups.items():
        if scene not in refs or not g:
            continue
        floor = float(refs[scene]["relMSE_floor"])
        top = max(b for (_, b) in g)
        e, m = min((x.rel_ms()[0], mm) for (mm, b), x in g.items() if b == top)
        ratio = floor / (e - floor) if e > floor else float("inf")
        lines.append("| %s | %s | %s | %s, %g s | %s | %.3f | %s |" % (
            scene, refs[scene]["source"].split(" (")[0], fmt_e(floor), m, top, fmt_e(e), ratio,
            "yes" if ratio <= 0.1 else "no"))
    lines.append("")
    # 5. Bootstrap share.
    shares = [(max(x.plan_share), scene, m, b) for scene, (g, _) in all_groups.items()
              for (m, b), x in g.items() if is_chain(m) and x.plan_share]
    if shares:
        s, scene, m, b = max(shares)
        lines.append("**Bootstrap share** (target: at most 5%% of every job): largest %.1f%% (%s, %s, %g s)."
                     % (100 * s, scene, m, b))
        lines.append("")
    return lines


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", required=True, help="directory for the pooled tables and the charts")
    ap.add_argument("--page", required=True, help="the Markdown page to write")
    ap.add_argument("--header", help="a Markdown file put at the top of the page")
    ap.add_argument("--keep", metavar="DIR", help="pooled tables of a previous page (its --out): their rows of "
                    "every (scene, method, budget) the eval directories do not have are kept")
    ap.add_argument("dirs", nargs="+", help="mltfarm eval output directories")
    a = ap.parse_args()
    if a.keep and os.path.realpath(a.keep) == os.path.realpath(a.out):
        sys.exit("results_page.py: --keep %s is --out: copy it first (the pooled tables are rewritten)" % a.keep)
    runs, refs, budgets, kinds, bands = pool(a.dirs, a.out, a.keep)
    subprocess.run([sys.executable, os.path.join(os.path.dirname(__file__), "charts.py"), a.out], check=True)
    out_rel = os.path.relpath(a.out, os.path.dirname(os.path.abspath(a.page)))
    lines = []
    if a.header:
        with open(a.header) as f:
            lines += f.read().rstrip("\n").split("\n") + [""]
    scenes = sorted({r["scene"] for r in runs})  # alphabetical, whatever order the directories came in
    all_groups = OrderedDict()
    body = []
    for scene in scenes:
        sec, g, methods = scene_section(scene, [r for r in runs if r["scene"] == scene], refs.get(scene),
                                        budgets, out_rel, [k for k in kinds if k["scene"] == scene],
                                        [x for x in bands if x["scene"] == scene])
        all_groups[scene] = (g, methods)
        body += sec
    lines += targets_section(all_groups, refs, budgets) + body
    with open(a.page, "w") as f:
        f.write("\n".join(lines) + "\n")
    print("wrote %s and %s/" % (a.page, a.out))


if __name__ == "__main__":
    main()
