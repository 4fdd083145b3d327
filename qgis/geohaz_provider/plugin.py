"""Registers the geohaz provider with QGIS Processing (desktop and qgis_process)."""
from qgis.core import QgsApplication

from .provider import GeohazProvider


class GeohazPlugin:
    def __init__(self, iface):
        self.iface = iface
        self.provider = None

    def initProcessing(self):  # noqa: N802 (QGIS calls it by this name, also in qgis_process)
        self.provider = GeohazProvider()
        QgsApplication.processingRegistry().addProvider(self.provider)

    def initGui(self):  # noqa: N802
        self.initProcessing()

    def unload(self):
        if self.provider is not None:
            QgsApplication.processingRegistry().removeProvider(self.provider)
