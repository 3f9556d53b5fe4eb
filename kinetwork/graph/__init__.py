"""The wiring: the model, its validation (topology: connection sets, spanning tree, loops) and
its files."""
