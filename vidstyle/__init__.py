"""vidstyle: learn a performer's action style from video and turn it into new 3D character motion.

Reference implementation of Chen (2012), "Augmenting the Creation of 3D Character Motion by Learning
from Video Data". Sub-packages own one concern each (see README and ``docs/design.md``).
"""

__version__ = "0.1.0"
