"""Reproductions of the seed paper's experiments (curvature estimation, boundary following)."""
