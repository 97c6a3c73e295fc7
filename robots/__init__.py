"""Bundled robot descriptions (URDF); see README.md in this folder."""
