"""A camera with its main lens focused elsewhere: ``Camera.with_optics`` and ``MainLens.focused_at``."""


def focused(camera, distance_mm: float):
    """``camera`` with its main lens focused at ``distance_mm`` from the sensor (b_U from the thin-lens equation)."""
    return camera.with_optics(camera.main_optics.focused_at(distance_mm, camera.mla_path_mm))
