"""AugMG (thesis 5.2): annotated transition frames -> 2D pose -> match against the mocap library
projected at that viewpoint -> reference point -> enhancement nodes in the motion graph.

Layers: :mod:`.library` (the demo mocap library), :mod:`.keypoints` (15 body keypoints),
:mod:`.projection` (facing-relative 2D projection and joint-angle features), :mod:`.index`
(kNN over the projected library, temporal coherence), :mod:`.enhance` (enhanced distance, reference
point, two-half transition), :mod:`.evaluate` (retrieval and transition error).
"""
