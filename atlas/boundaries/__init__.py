"""Basin boundaries: the exact ones behind one interface (exact.py), the RK4 map's traced
separatrices (trace.py), and the certificate that compares the two (certificate.py)."""
