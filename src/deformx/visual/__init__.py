"""The visual layer: tube meshes of rods (``tube``), a pinhole camera (``camera``), the fast
renderer on MuJoCo (``fast``: RGB, z-depth, instance masks, keypoints), rendered runs
(``movie``), plots and videos of recorded runs (``plots``). Importing this package loads no
plotting or rendering library; each submodule imports its own (matplotlib, MuJoCo) when used.
See ``docs/visual.md``."""
