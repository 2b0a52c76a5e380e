"""The serving side every bus shares: the transport that serves sessions over pseudo-terminals
and TCP on loopback with the simulation running in real time (:mod:`.transport`), and the twin
every bus's slave or server wraps (:mod:`.twin`)."""
