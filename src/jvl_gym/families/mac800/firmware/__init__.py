"""The MAC800 firmware as compiled kernels: the main filter, current loop, function blocks,
modes, zero searches, monitors and the sample buffer (MAC800 register overview §1.2)."""
