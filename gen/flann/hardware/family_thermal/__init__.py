"""A sensor family with temperature compensation: per-sensor temperature coefficients in weight memories."""
