"""Model answers: what a parser is asked for and reads out (``spec``), the pieces of free text it
reads them from (``text``), and the schema check every parser ends with (``validation``).

Pure: no files, no network, no plugin lookups.
"""
