# Stub of pinocchio.visualize: only the Meshcat visualiser workbench draws with.

from typing import Any

import numpy.typing as npt
from pinocchio import Data, GeometryData, GeometryModel, Model

class MeshcatVisualizer:
    viewer: Any  # a meshcat.Visualizer
    model: Model
    data: Data
    visual_model: GeometryModel
    visual_data: GeometryData
    def __init__(
        self,
        model: Model,
        collision_model: GeometryModel | None = ...,
        visual_model: GeometryModel | None = ...,
        copy_models: bool = ...,
        data: Any = ...,
        collision_data: Any = ...,
        visual_data: Any = ...,
    ) -> None: ...
    def initViewer(
        self,
        viewer: Any = ...,
        open: bool = ...,
        loadModel: bool = ...,
        zmq_url: Any = ...,
    ) -> None: ...
    def loadViewerModel(
        self, rootNodeName: str = ..., color: Any = ..., **kwargs: Any
    ) -> None: ...
    def display(self, q: npt.ArrayLike | None = ...) -> None: ...
    def getViewerNodeName(self, geometry_object: Any, geometry_type: Any) -> str: ...
