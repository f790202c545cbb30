"""Report: bead metrics, the seed's figures, a rendered picture and summary.json."""
