"""Tests of kinetwork.solver (a package, so that test files may share a name with those of
another layer: components/test_signals.py, equations/test_signals.py)."""
