"""One owner module per artifact: a typed object, ``read_*`` / ``write_*``, a ``kind`` + ``schema_version``
header, and validation of every field that raises :class:`FormatError` naming the file and the field."""

from ._base import FormatError, Fields, check_array, check_header, header, read_json_document, write_json_document

__all__ = ["FormatError", "Fields", "check_array", "check_header", "header", "read_json_document",
           "write_json_document"]
