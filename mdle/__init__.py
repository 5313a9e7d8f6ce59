"""mdle: an interpreter for MDLe, the extended Motion Description Language.

Text flows one way: ``.mdle`` source -> syntax tree -> checked program -> runtime ->
backend (simulated or real robot), with events out to traces and plots. Heavy
modules (numpy, shapely, matplotlib) are imported lazily by the stages that need them,
so ``mdle check`` starts fast.
"""

__version__ = "0.1.0"

__all__ = ["__version__"]
