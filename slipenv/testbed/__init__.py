"""A virtual single-wheel test bed (Reina §3), the test-bed CSV format and force-law fitting."""
