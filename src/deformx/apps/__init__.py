"""Applications built on the engine and the visual layer: YAML scenes, micro-benchmarks
(later: learning, dataset generation, perception). Submodules are imported on use."""
