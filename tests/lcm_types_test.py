#!/usr/bin/env python3
"""The Python module generated from lcm/*.lcm encodes and decodes like the C++ one."""
import sys

sys.path.insert(0, sys.argv[1])
from kincal import params_t  # noqa: E402

p = params_t()
p.schema_version = 1
p.model = "unicycle"
p.estimator = "dd2"
p.num_params = 2
p.names = ["k_v", "k_omega"]
p.units = ["1", "1"]
p.values = [0.91, 0.84]
p.sigmas = [0.004, 0.006]
p.covariance = [[1.6e-5, 0.0], [0.0, 3.6e-5]]
p.update_count = 10
p.status = params_t.STATUS_CONVERGED
q = params_t.decode(p.encode())
assert q.names == p.names and list(q.values) == p.values, (q.names, q.values)
assert [list(r) for r in q.covariance] == p.covariance
print("1 passed, 0 failed")
