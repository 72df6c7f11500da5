"""The visual layer: plots and videos of recorded runs (``plots``); later tube meshes,
skinning, renderers and exporters. Importing this package loads no plotting or rendering
library; each submodule imports its own (matplotlib, MuJoCo, Blender) when used."""
