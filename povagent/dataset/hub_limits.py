"""How much a Hub download may take: an overall deadline, a size cap per file and in total.

The same three numbers are ``povagent download``'s ``--deadline``, ``--max-file-mib`` and
``--max-total-mib`` and a pipeline's ``dataset: {hub: ..., download: {deadline_s, max_file_mib,
max_total_mib}}``. The defaults leave room for the real release (516 MiB in 2,332 PNGs of about
226 KiB, the largest file a few MiB) on a slow link and stop a server that would fill the disk
or never finish:

* ``deadline_s`` = 3600: an hour for the whole download (metadata and every file);
* ``max_file_mib`` = 64: no file of the release comes near;
* ``max_total_mib`` = 4096: eight times the release.

The caps are checked against the tree listing before any byte is fetched, and a file is cut off
as soon as it sends more than the listing said. This module only holds the numbers.
"""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict, Field

#: Upper bounds of the settings themselves (a config is untrusted input too).
MAX_DEADLINE_S = 7 * 24 * 3600.0
MAX_MIB = 1024 * 1024


class DownloadLimits(BaseModel):
    """Bounds of one Hub download (see the module docstring for the defaults and why)."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    #: Seconds the whole download may take, metadata included.
    deadline_s: float = Field(3600.0, gt=0, le=MAX_DEADLINE_S)
    #: Largest single file, in MiB.
    max_file_mib: float = Field(64.0, gt=0, le=MAX_MIB)
    #: Largest total of the files a download selects, in MiB.
    max_total_mib: float = Field(4096.0, gt=0, le=MAX_MIB)

    @property
    def max_file_bytes(self) -> int:
        """:attr:`max_file_mib` in bytes."""
        return int(self.max_file_mib * 2**20)

    @property
    def max_total_bytes(self) -> int:
        """:attr:`max_total_mib` in bytes."""
        return int(self.max_total_mib * 2**20)
