"""Mass-proportional damping D = gamma*M (report eq. 60), scene table [damping]."""

from pdfem.effects.base import Effect


class Damping(Effect):
    """Enters the velocity update through c1, c2 (eqs. 70-71); dissipation is accumulated
    per body by the integration kernel."""

    name = "damping"

    def __init__(self, table, scene):
        super().__init__(table, scene)
        self.gamma = float(table["gamma"])
