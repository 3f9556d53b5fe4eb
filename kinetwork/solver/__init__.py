"""Running a System: the one integrator driver, the method table, the JIT cache, Results."""
