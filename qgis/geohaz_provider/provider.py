"""The Processing provider `geohaz`: algorithms geohaz:debris_runout, geohaz:ensemble, geohaz:report."""
from qgis.core import QgsProcessingProvider

from .algorithms import DebrisRunoutAlgorithm, EnsembleAlgorithm, ReportAlgorithm


class GeohazProvider(QgsProcessingProvider):
    def id(self):
        return "geohaz"

    def name(self):
        return "geohaz"

    def longName(self):  # noqa: N802
        return "geohaz landslide models"

    def loadAlgorithms(self):  # noqa: N802
        for alg in (DebrisRunoutAlgorithm(), EnsembleAlgorithm(), ReportAlgorithm()):
            self.addAlgorithm(alg)
