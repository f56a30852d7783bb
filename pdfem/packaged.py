"""The scenes packaged with pdfem (``pdfem/scenes/``)."""

from importlib import resources

# The scene ``python -m pdfem`` runs when it gets none
DEFAULT_SCENE = "shot912.toml"


def default_scene_path():
    """Path of the scene that runs when ``python -m pdfem`` gets no argument."""
    return str(resources.files("pdfem") / "scenes" / DEFAULT_SCENE)
