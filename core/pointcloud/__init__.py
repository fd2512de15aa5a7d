"""Point-cloud smoothing through the RFS mesh (paper section 7)."""

from .spanning_tree import emst
