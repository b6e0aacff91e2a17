"""Statistical action models (Du 2014, Motion Graphs++): instances, DTW alignment, functional PCA, GMM.

:class:`ActionModel` (scikit-learn conventions) learns one model per action label from labelled mocap;
``sample`` draws new instances as BVH-ready motion, ``encode`` / ``decode`` / ``log_prior`` serve a later
fit to video. See ``docs/actionmodel.md``.
"""

from .instances import Instance, InstanceSet, cut_instances, load_labelled
from .model import ActionModel, Aligned, LabelModel

__all__ = ["ActionModel", "Aligned", "Instance", "InstanceSet", "LabelModel", "cut_instances", "load_labelled"]
