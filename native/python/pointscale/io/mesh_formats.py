"""Mesh formats: OBJ and OFF (parsed with numpy, see obj.py and off.py for why not trimesh) and
STL (through trimesh). Each reader keeps the file's vertex order."""
from .obj import read_obj, write_obj
from .off import read_off, write_off
from .stl import read_stl, write_stl

__all__ = ["read_obj", "read_off", "read_stl", "write_obj", "write_off", "write_stl"]
