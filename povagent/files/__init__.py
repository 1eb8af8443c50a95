"""The ground floor: safe file access and redaction, what every other room stands on.

Confined reads (``confined_read``: bounded, never through a planted link, never a FIFO or a
device), confined writes (``confined_write``: atomic, inside the folder the user named), the
run-folder lock (``folder_lock``) and the redactor (``redaction``: no secret reaches a file or
a terminal). Every room that touches a file a user or a server handed it imports from here.

It imports nothing of povagent but :mod:`povagent.errors`; nothing here may import a room above.
"""
