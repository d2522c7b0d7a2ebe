"""Basin stability across parameters, exactly: ``atlas stability`` (a study without a grid)."""
