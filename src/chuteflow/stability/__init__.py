"""Linear stability of steady chute flows (paper §4, Appendices A–B)."""
from .operator import Pencil, StabilityOperator, base_on_grid, operator
from .eigen import ShiftInvert, qz
from .modes import (Mode, choose_n, least_stable, mode_near, spectrum, stability_operator,
                    tail)
from .dispersion import (BranchTracker, NullVectors, branch_mode, critical_k, crossings,
                         dispersion, first_order, null_vectors)
