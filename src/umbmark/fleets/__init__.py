"""A fleet of robots: every recording calibrated by what it holds, on a distributed engine."""
