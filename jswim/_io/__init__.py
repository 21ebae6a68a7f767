"""The bottom layer for folder I/O, JAX-free: atomic writes and strict JSON (:mod:`jswim._io.atomic`)."""
