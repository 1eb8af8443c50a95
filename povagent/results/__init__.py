"""Result rows: povagent's own row format (``rows``) and the official prediction format
(``official_format``), read and written.
"""
