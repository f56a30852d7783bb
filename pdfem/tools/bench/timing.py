"""The timing of one benchmark figure: the median of repeated calls after an untimed one."""

import statistics
import time


def median_call(fn, args, repeat, clock=time.perf_counter, warm=True):
    """Median seconds, by ``clock``, of ``repeat`` calls of fn(*args), after one untimed call
    (numba compile or cache load, first touch of the arrays) unless ``warm`` is False."""
    if warm:
        fn(*args)
    times = []
    for _ in range(repeat):
        t0 = clock()
        fn(*args)
        times.append(clock() - t0)
    return statistics.median(times)
