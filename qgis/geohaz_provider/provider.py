"""The Processing provider `geohaz`: algorithms geohaz:debris_runout, geohaz:ensemble, geohaz:calibrate,
geohaz:slope_stability, geohaz:report."""
from qgis.core import QgsProcessingProvider

from .algorithms import DebrisRunoutAlgorithm, EnsembleAlgorithm, ReportAlgorithm
from .calibration import CalibrateAlgorithm
from .stability import SlopeStabilityAlgorithm


class GeohazProvider(QgsProcessingProvider):
    def id(self):
        return "geohaz"

    def name(self):
        return "geohaz"

    def longName(self):  # noqa: N802
        return "geohaz landslide models"

    def loadAlgorithms(self):  # noqa: N802
        for alg in (DebrisRunoutAlgorithm(), EnsembleAlgorithm(), CalibrateAlgorithm(), SlopeStabilityAlgorithm(),
                    ReportAlgorithm()):
            self.addAlgorithm(alg)
