"""jswim: a large language model teaches model microswimmers to swim."""

__version__ = "0.1.0"
