"""The exact basin boundaries (stable manifolds), the traced separatrices, the certificate."""
