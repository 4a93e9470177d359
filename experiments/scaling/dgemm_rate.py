#!/usr/bin/python3
"""The dense matrix-product rate of one core: the ceiling the scaling README compares the
sparse factorisations' rate against (numpy's `@`, i.e. the BLAS that run.sh installs,
Debian's serial OpenBLAS).

    /usr/bin/python3 experiments/scaling/dgemm_rate.py [--n 2000] [--repeats 5]

Prints the median time of --repeats products of two n x n random matrices (after one warm-up)
and the rate 2 n^3 / time in GFlop/s.
"""
import argparse
import statistics
import time

import numpy as np


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=2000)
    ap.add_argument("--repeats", type=int, default=5)
    a = ap.parse_args()
    if a.n < 1 or a.repeats < 1:
        ap.error("--n and --repeats must be >= 1")
    rng = np.random.default_rng(1)
    x, y = rng.random((a.n, a.n)), rng.random((a.n, a.n))
    x @ y
    times = []
    for _ in range(a.repeats):
        t = time.perf_counter()
        x @ y
        times.append(time.perf_counter() - t)
    med = statistics.median(times)
    print("dgemm n=%d: median %.3f s of %d, %.1f GFlop/s" % (a.n, med, a.repeats,
                                                             2.0 * a.n ** 3 / med / 1e9))


if __name__ == "__main__":
    main()
