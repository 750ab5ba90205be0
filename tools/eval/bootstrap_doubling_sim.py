#!/usr/bin/env python3
# Optional-stopping bias of the budgeted doublings of a multi-length bootstrap (docs/CHAINS.md).
# Optional-stopping bias of the bootstrap's budgeted doublings (mmlt: several lengths).
import numpy as np
rng = np.random.default_rng(5)
def dA(n): return rng.exponential(1.0, n)
def dB(n):
    p, v = 1e-4, 300
    x = rng.exponential(1.0, n) * (1 - p * v); m = rng.random(n) < p; x[m] += v; return x
def dC(n):
    a = 2.5; return (rng.pareto(a, n) + 1) / (a / (a - 1))
draws = [dA, dB, dC]; cost = np.array([1.0, 2.0, 3.0])
N = 8192
budget = N * cost.sum()
T = 6000
est = np.zeros((T, 3)); ns = np.zeros((T, 3))
for t in range(T):
    samples = [d(N // 4) for d in draws]
    while True:
        se2 = np.array([s.var(ddof=1) / s.size for s in samples])
        n = np.array([s.size for s in samples])
        used = (n * cost).sum()
        order = np.argsort(-(se2 / (n * cost)), kind='stable')
        done = True
        for l in order:
            if used + n[l] * cost[l] <= budget:
                samples[l] = np.concatenate([samples[l], draws[l](n[l])]); done = False; break
        if done: break
    est[t] = [s.mean() for s in samples]; ns[t] = [s.size for s in samples]
m = est.mean(axis=0); se = est.std(axis=0) / np.sqrt(T)
print("per length bias %:", np.round(100 * (m - 1), 3), "+-", np.round(100 * se, 3), "mean n:", ns.mean(axis=0))
tot = est.sum(axis=1) / 3
print("total bias %% %.3f +- %.3f, sd %.3f%%" % (100 * (tot.mean() - 1), 100 * tot.std() / np.sqrt(T), 100 * tot.std()))
