"""The MIS/SMC firmware at the 1 ms outer sample: profile generator, modes, monitoring, inputs."""
