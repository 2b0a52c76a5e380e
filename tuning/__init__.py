"""jvl_gym tuning toolkit: identification, synthesis, quantisation and verification."""
