"""Model patching: keeping a compiled model equal to a fresh compile without compiling."""
