"""Physics of a MAC800 and its surroundings that is its own: encoder (8000 counts/rev, index
pulse) and the winding temperature; the PMSM coil, mechanics and DC bus are the MAC050–141
plant's register-independent kernels (the same physics)."""
