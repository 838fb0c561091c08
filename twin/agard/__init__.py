"""AGARD-AR-144 measurements: describing function, noise level, dynamic threshold, OMCT, SNR."""
