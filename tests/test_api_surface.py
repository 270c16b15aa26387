"""The curated public surface: removing or adding a name of ``boustro.__all__`` fails here until
this inventory is edited in the same change (a deliberate API decision, never an accident)."""

import boustro

SURFACE = {
    # errors
    "BoustroError", "InvalidParameterError", "InvalidPolygonError", "MissingDependencyError",
    "NoTransectError", "NonConvexPolygonError", "PolygonFileError", "ProblemTooLargeError",
    # geometry
    "Frame", "HalfPlanes", "Polygon", "Region", "halfplanes",
    # models
    "DEFAULT_SMOOTHING", "ExactModel", "PaperModel", "RegionExactModel", "RegionSoftModel",
    "SmoothModel", "TransectLengths", "TransectModel", "exact_chords", "paper_lengths",
    "region_segments", "smooth_lengths", "smoothing_from_temperature",
    "temperature_from_smoothing", "transect_positions",
    # objectives and scoring
    "FewestTransects", "ShortestPath", "SmithFitness", "get_objective", "objective_sense",
    "path_length", "register_objective", "smith_fitness", "Score", "Segments", "make_model",
    "score", "transect_segments",
    # optimisers
    "GRID_200", "OptimizeResult", "TemperatureSchedule", "best_offset",
    "fewest_transects_optimum", "global_optimum", "gradient_descent", "grid_search", "hybrid",
    "register_method", "shortest_path_optimum",
    # plans and sensors
    "Plan", "PlanStats", "build_plan", "coverage", "guaranteed_segments", "optimize_region",
    "plan_region", "Camera", "Swath",
    # batch and the geo stack (resolved on first use: import boustro loads neither)
    "batch", "plan_area",
    "__version__",
}  # fmt: skip


def test_public_surface_is_the_inventory():
    assert set(boustro.__all__) == SURFACE
    assert len(boustro.__all__) == len(SURFACE)  # no name listed twice


def test_every_public_name_resolves_and_is_documented():
    for name in boustro.__all__:
        obj = getattr(boustro, name)
        if callable(obj) and not name.startswith("_"):
            assert (obj.__doc__ or "").strip(), f"boustro.{name} has no docstring"
