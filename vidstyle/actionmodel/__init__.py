"""Statistical action models (Du 2014, Motion Graphs++): instances, DTW alignment, functional PCA, GMM.

:class:`ActionModel` (scikit-learn conventions) learns one model per action label from labelled mocap;
``sample`` draws new instances as BVH-ready motion, ``encode`` / ``decode`` / ``log_prior`` serve a later
fit to video. See ``docs/actionmodel.md``. Defaults: :mod:`vidstyle.actionmodel.defaults`.
"""

from typing import TYPE_CHECKING

from ..lazy import lazy_package

if TYPE_CHECKING:  # pragma: no cover
    from .instances import Instance, InstanceSet, cut_instances, load_labelled
    from .model import ActionModel, Aligned, LabelModel, fit_gmm_bic

# names load their submodule on first use (:mod:`vidstyle.lazy`): the CLI reads ``defaults`` at start-up
_WHERE = {
    "ActionModel": "model", "Aligned": "model", "LabelModel": "model", "fit_gmm_bic": "model",
    "Instance": "instances", "InstanceSet": "instances", "cut_instances": "instances", "load_labelled": "instances",
}
__getattr__ = lazy_package(__name__, _WHERE)

__all__ = ["ActionModel", "Aligned", "Instance", "InstanceSet", "LabelModel", "cut_instances", "fit_gmm_bic",
           "load_labelled"]
