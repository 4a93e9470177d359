"""Calls on several threads at once give what the same calls give one after another (the GIL
is released while they solve; each call owns all its state)."""
import threading

import numpy as np

import knitsim

STIFFNESS = [500, 640, 780, 920, 1060, 1200]


def sweep(values, out, integrator=None):
    for k in values:
        out[k] = knitsim.drape("four_corner", {"model.stiffness": k}, integrator)


def test_two_threads_give_the_serial_results():
    serial = {}
    sweep(STIFFNESS, serial)
    parallel = {}
    threads = [threading.Thread(target=sweep, args=(STIFFNESS[i::2], parallel)) for i in (0, 1)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert sorted(parallel) == sorted(serial)
    for k in STIFFNESS:
        assert np.array_equal(parallel[k].positions, serial[k].positions), k
        assert parallel[k].summary["steps"] == serial[k].summary["steps"]
    # The sweep is a sweep: more stiffness, less sag.
    sags = [serial[k].centre_sag for k in STIFFNESS]
    assert sags == sorted(sags, reverse=True)


def test_threads_with_different_integrators_and_scenes():
    jobs = [("four_corner", "cvode-bdf"), ("two_corner", None), ("four_corner", "static"),
            ("two_corner", "cvode-bdf")]
    serial = [knitsim.drape(s, None, i) for s, i in jobs]
    results = [None] * len(jobs)

    def run(k):
        results[k] = knitsim.drape(jobs[k][0], None, jobs[k][1])

    threads = [threading.Thread(target=run, args=(k,)) for k in range(len(jobs))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for a, b in zip(results, serial):
        assert a.status == b.status and np.array_equal(a.positions, b.positions)
