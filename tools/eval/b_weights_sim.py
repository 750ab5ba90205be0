#!/usr/bin/env python3
# b estimators under a stratified bootstrap + i.i.d. large steps (docs/CHAINS.md, "b's weights biased it low"):
# inverse variance on all of c (d5, the rule before), pooled by count, outlier-robust weights, tail split (now).
# Usage: python3 tools/eval/b_weights_sim.py   (numpy; a few minutes)
import numpy as np
rng = np.random.default_rng(7)
G = 16
def strat_bulk(rows, kind):
    u = (np.arange(rows)[:, None] + rng.random((1, G))) / rows
    u = u[rng.permutation(rows)]
    if kind == 'exp': return -np.log1p(-u)
    if kind == 'light': return np.where(u < 0.02, 50.0, 0.0)   # light seen in 2% of the film, stratified
def iid_bulk(n, kind):
    u = rng.random(n)
    return -np.log1p(-u) if kind == 'exp' else np.where(u < 0.02, 50.0, 0.0)
def est(c, L, N0, NL):
    b0 = c.mean(); gm = c.reshape(-1, G).mean(axis=0)
    v0 = ((gm - b0) ** 2).sum() / (G * (G - 1)); s2 = c.var(ddof=1); bL = L.mean()
    g = v0 / (s2 / N0) if s2 > 0 else 1
    d5 = (lambda w: w * b0 + (1 - w) * bL)(1 / (1 + g * NL / N0))
    pooled = (c.sum() + L.sum()) / (N0 + NL)
    tau = np.sort(c)[-16]; cc = np.minimum(c, tau)
    gmc = cc.reshape(-1, G).mean(axis=0); v0c = ((gmc - cc.mean()) ** 2).sum() / (G * (G - 1)); s2c = cc.var(ddof=1)
    gc = v0c / (s2c / N0) if s2c > 0 else 1
    robust = (lambda w: w * b0 + (1 - w) * bL)(1 / (1 + gc * NL / N0))
    Lc = np.minimum(L, tau)
    wc = 1 / (1 + gc * NL / N0)
    split = wc * cc.mean() + (1 - wc) * Lc.mean() + (np.maximum(c - tau, 0).sum() + np.maximum(L - tau, 0).sum()) / (N0 + NL)
    return d5, pooled, robust, split
N0, NL = 16 * 1024, 6 * 16 * 1024
for kind, p, v in [('exp', 1e-5, 2000), ('exp', 1e-4, 300), ('exp', 0, 0), ('light', 0, 0), ('light', 1e-5, 5000)]:
    T = 2000; r = []
    for t in range(T):
        c = strat_bulk(N0 // G, kind).ravel() * (1 - p * v); m = rng.random(N0) < p; c[m] += v
        L = iid_bulk(NL, kind) * (1 - p * v); m = rng.random(NL) < p; L[m] += v
        r.append(est(c, L, N0, NL))
    r = np.array(r); tm = 1.0 if kind == 'exp' else 1.0
    mu = r.mean(axis=0); sd = r.std(axis=0); se = sd / np.sqrt(T)
    print(kind, p, v, " ".join(f"{n}: bias {100*(m/tm-1):+.3f}+-{100*s/tm:.3f} sd {100*d/tm:.3f}" for n, m, s, d in zip(["d5", "pooled", "robust", "split"], mu, se, sd)), flush=True)
