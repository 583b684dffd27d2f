"""Import meshcat quietly (0.3 imports the deprecated ``zmq.eventloop.ioloop``)."""

import warnings

with warnings.catch_warnings():
    warnings.simplefilter("ignore", DeprecationWarning)
    import meshcat
    import meshcat.visualizer

__all__ = ["meshcat"]
