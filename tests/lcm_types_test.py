#!/usr/bin/env python3
"""The Python module generated from lcm/*.lcm encodes and decodes like the C++ one."""
import sys

sys.path.insert(0, sys.argv[1])
from kincal import calibration_t, params_t  # noqa: E402

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
p.source = params_t.SOURCE_BATCH
q = params_t.decode(p.encode())
assert q.names == p.names and list(q.values) == p.values, (q.names, q.values)
assert [list(r) for r in q.covariance] == p.covariance
assert q.source == params_t.SOURCE_BATCH

# The batch tier's message lays its parameters out as params_t does.
c = calibration_t()
c.schema_version = 1
c.sequence = 3
c.ok = 1
c.calibration_sequence = 3
c.model = "unicycle+time_offset"
c.num_effects = 1
c.effects = ["time_offset"]
c.num_params = 3
c.names = ["k_v", "k_omega", "delay_s"]
c.units = ["1", "1", "s"]
c.values = [0.9, 0.85, 0.2]
c.sigmas = [0.01, 0.01, 0.005]
c.covariance = [[1e-4, 0, 0], [0, 1e-4, 0], [0, 0, 2.5e-5]]
c.num_accepted = 1
c.accepted = ["time_offset"]
c.accepted_evidence = ["time_offset accepted (held-out gain 0.6)"]
d = calibration_t.decode(c.encode())
assert d.names == c.names and list(d.values) == c.values and d.accepted == c.accepted
assert [list(r) for r in d.covariance] == c.covariance
print("2 passed, 0 failed")
