"""Assemblies of parts from the user's models, fastened one fastener at a time, with friction."""

__all__: list[str] = []
