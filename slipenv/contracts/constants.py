"""Physical constants every layer shares, defined once."""

G_MPS2 = 9.81
"""[m/s²] gravity of every simulated world (``setGravity``, the wheel test bed) and of every
static load derived from a mass. Lindgren's accelerometer model keeps standard gravity
(9.80665), the unit its Eq. 14 accelerations are given in."""
