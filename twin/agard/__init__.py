"""AGARD-AR-144 measurements (describing functions first; more come with issue 4)."""
