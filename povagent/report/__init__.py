"""Reports: the paper's tables, statistics and the HTML report."""
