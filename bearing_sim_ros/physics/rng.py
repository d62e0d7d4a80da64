"""Counter-based random numbers: a value is a pure function of (seed, stream, index).

Why not a stateful generator: the simulator must give the same samples whether it advances in
one call or in many chunks, and a tier may be rebuilt mid-run (fidelity switching).  A hash of
the sample index gives that for free.  splitmix64 (Steele, Lea, Flood 2014) passes BigCrush
when used as a hash of a counter.
"""
from numba import njit, uint64

_GOLDEN = uint64(0x9E3779B97F4A7C15)
_M1 = uint64(0xBF58476D1CE4E5B9)
_M2 = uint64(0x94D049BB133111EB)
_INV53 = 1.0 / 9007199254740992.0  # 2**-53


@njit(cache=True, inline="always")
def _mix(z):
    z = (z ^ (z >> uint64(30))) * _M1
    z = (z ^ (z >> uint64(27))) * _M2
    return z ^ (z >> uint64(31))


@njit(cache=True, inline="always")
def uniform(seed, stream, index):
    """Uniform in [0, 1) from three integers (seed, stream, index >= 0)."""
    z = _mix(uint64(seed) * _GOLDEN + uint64(stream) * _M2 + uint64(0x632BE59BD9B4E019))
    z = _mix(z + uint64(index) * _GOLDEN)
    return float(z >> uint64(11)) * _INV53
