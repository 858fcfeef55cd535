"""Suite-wide test settings.

Hypothesis' per-example deadline is a timing assertion: on a loaded 2-core
machine an example that takes 0.2 ms alone can take 400 ms, and the test
would fail for the machine's sake, not the code's. Speed lives in ``bench/``,
so the suite runs with no deadline (and no "too slow" health check).
"""

from hypothesis import HealthCheck, settings

settings.register_profile(
    "credal",
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
)
settings.load_profile("credal")
