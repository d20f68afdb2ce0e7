"""Download, verify and unpack the paper's real datasets (python -m data_fetch)."""
