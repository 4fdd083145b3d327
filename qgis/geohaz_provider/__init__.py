"""QGIS plugin: the geohaz Processing provider (docs/qgis.md)."""


def classFactory(iface):  # noqa: N802 (QGIS's name)
    from .plugin import GeohazPlugin
    return GeohazPlugin(iface)
