"""A2 plugins: the paper's models as ordinary ncperf plugins.

* :mod:`plugins.tangential` -- model 1, tangential discontinuities (eq. 1-10)
* :mod:`plugins.curvature` -- model 2, curvature discontinuities (eq. 11-15)
* :mod:`plugins.ncu_capacity` -- model 3, block cycle time (eq. 16)
* :mod:`plugins.exact_stop` -- exact stops and dwells the program asks for
* :mod:`plugins.feed_limit` -- no block faster than its axes' feed limits
* :mod:`plugins.rotary` -- nor faster than its rotary axes can turn
"""
