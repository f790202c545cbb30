"""Path: bead geometry by arc length (corners blended, orientation interpolated) and its time law."""
