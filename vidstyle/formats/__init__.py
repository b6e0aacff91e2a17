"""One owner module per artifact: a typed object, ``read_*`` / ``write_*``, a ``kind`` + ``schema_version``
header, and validation of every field that raises :class:`FormatError` naming the file and the field.

=========================================  ===============================  ==================================
file                                       kind (schema_version)            owner
=========================================  ===============================  ==================================
labels ``<video id>.json``, mocap          ``vidstyle.labels`` (2; 1 = no   :mod:`vidstyle.formats.labels`
``<take>.labels.json``                     header)
recognised labels (``vidstyle recognize``) ``vidstyle.recognised_labels``   :mod:`vidstyle.formats.recognised`
                                           (2; 1 = no header)
dataset manifest ``dataset.json``          ``vidstyle.dataset`` (2; 1)      :mod:`vidstyle.formats.dataset`
action sequence (``generate --format       ``vidstyle.sequence`` (1)        :mod:`vidstyle.formats.sequence`
json``)
style ``style.json``                       ``vidstyle.style`` (1)           :mod:`vidstyle.formats.style`
render ground truth ``<video>.truth.npz``  ``vidstyle.render_truth`` (2; 1) :mod:`vidstyle.formats.truth`
synthesised motion ``<out>.labels.json``   ``vidstyle.labels`` (2) + walk   :mod:`vidstyle.formats.walk`
(``vidstyle synthesize``)                  fields
keyframes ``K.json`` (``synthesize         ``vidstyle.keyframes`` (1; 1 =   :mod:`vidstyle.formats.keyframes`
--keyframes``)                             no header)
metrics (recognition, style, motion,       ``vidstyle.metrics.<what>`` (1)  :mod:`vidstyle.formats.metrics`
headline)
=========================================  ===============================  ==================================
"""

from ._base import (
           Fields,
           FormatError,
           check_array,
           check_header,
           header,
           read_json_document,
           write_json_document,
)

__all__ = ["FormatError", "Fields", "check_array", "check_header", "header", "read_json_document",
           "write_json_document"]
