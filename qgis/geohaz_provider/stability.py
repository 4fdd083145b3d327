"""geohaz:slope_stability, the rainfall-driven infinite-slope stability map (slope-stability,
docs/stability.md), run as the app: the Processing inputs become its --set keys. Progress follows
the app's progress lines (simulated time); Cancel stops the app."""
import json
import os
import re
import shutil
import subprocess
import tempfile

from qgis.core import (QgsFillSymbol, QgsProcessingContext, QgsProcessingException,
                       QgsProcessingOutputMultipleLayers, QgsProcessingOutputNumber, QgsProcessingOutputRasterLayer,
                       QgsProcessingOutputVectorLayer, QgsProcessingParameterFolderDestination,
                       QgsProcessingParameterNumber, QgsProcessingParameterRasterLayer, QgsProcessingParameterString,
                       QgsProcessingUtils, QgsSingleSymbolRenderer, QgsVectorLayer)

from .algorithms import _Base, _file_of, _load_maps
from .calibration import split_set

# (parameter, config key, description with unit, default (the app's), minimum, decimals)
NUMBERS = [
    ("SOIL_DEPTH", "soil.depth", "Soil depth Z: vertical depth of the failure plane (m)", 1.5, 0.0, 3),
    ("MIN_SLOPE", "soil.min_slope", "Flattest slope with a soil cover (deg)", 0.0, 0.0, 2),
    ("MAX_SLOPE", "soil.max_slope", "Steepest slope with a soil cover (deg)", 60.0, 0.0, 2),
    ("COHESION", "soil.cohesion", "Effective cohesion c' (Pa)", 2000.0, 0.0, 1),
    ("FRICTION_ANGLE", "soil.friction_angle", "Effective friction angle phi' (deg)", 35.0, 0.0, 2),
    ("UNIT_WEIGHT_MOIST", "soil.unit_weight_moist", "Unit weight above the water table (N/m³)", 18000.0, 0.0, 1),
    ("UNIT_WEIGHT_SATURATED", "soil.unit_weight_saturated", "Saturated unit weight (N/m³)", 20000.0, 0.0, 1),
    ("CONDUCTIVITY", "hydrology.conductivity", "Saturated hydraulic conductivity K_s (m/s)", 1e-5, 0.0, 12),
    ("DIFFUSIVITY", "hydrology.diffusivity", "Hydraulic diffusivity D_0 (m²/s)", 5e-5, 0.0, 12),
    ("WATER_TABLE_DEPTH", "hydrology.water_table_depth", "Initial water-table depth d below the ground (m)", 1.5,
     0.0, 3),
    ("RAIN_STEP", "rain.step", "Length of each rain step (s)", 3600.0, 0.0, 1),
    ("TIME_STEP", "run.time_step", "Evaluation step of FS (s)", 3600.0, 0.0, 1),
]
MAPS = ["fs_min", "failure_time", "max_pressure_head", "slope"]


class SlopeStabilityAlgorithm(_Base):
    """geohaz:slope_stability: DSM, soil parameters and a rain scenario as Processing inputs."""

    def name(self):
        return "slope_stability"

    def displayName(self):  # noqa: N802
        return "Rainfall slope-stability map"

    def shortHelpString(self):  # noqa: N802
        return ("Where the soil cover of a DSM fails during a rainstorm (slope-stability, docs/stability.md): "
                "Iverson (2000) infiltration into an infinite slope, as in TRIGRS. Outputs, loaded with styles: "
                "the minimum factor of safety (fs_min), the time of first failure (failure_time, s), the largest "
                "pressure head (m), the slope (deg), and the failed cells as release polygons (release.gpkg, "
                "attribute thickness in m normal to the slope) that debris runout reads as its release. "
                "Rain intensities in m/s (1 mm/h = 2.778e-7 m/s). Units SI.")

    def initAlgorithm(self, config=None):  # noqa: N802
        P = self.addParameter
        P(QgsProcessingParameterRasterLayer("DSM", "DSM (elevation, m; projected CRS)"))
        P(QgsProcessingParameterRasterLayer("SOIL_DEPTH_RASTER", "Soil depth raster on the DSM grid (m), instead of "
                                            "the constant depth", optional=True))
        for name, _, desc, default, lo, decimals in NUMBERS:
            p = QgsProcessingParameterNumber(name, desc, QgsProcessingParameterNumber.Double, default, minValue=lo)
            p.setMetadata({"widget_wrapper": {"decimals": decimals}})
            P(p)
        P(QgsProcessingParameterString("RAIN_INTENSITY", "Rain intensity of each step (m/s, comma-separated)",
                                       "2.78e-6"))
        P(QgsProcessingParameterNumber("DURATION", "Simulated time (s); 0: the end of the rain",
                                       QgsProcessingParameterNumber.Double, 0.0, minValue=0.0))
        P(QgsProcessingParameterString("SET", "Other config keys (key=value; separated by ';')", optional=True))
        P(QgsProcessingParameterFolderDestination("OUTPUT", "Output folder"))
        self.addOutput(QgsProcessingOutputRasterLayer("FS_MIN", "Minimum factor of safety"))
        self.addOutput(QgsProcessingOutputRasterLayer("FAILURE_TIME", "Time of first failure (s)"))
        self.addOutput(QgsProcessingOutputVectorLayer("RELEASE", "Release polygons"))
        self.addOutput(QgsProcessingOutputMultipleLayers("MAPS", "Maps"))
        self.addOutput(QgsProcessingOutputNumber("FAILED_CELLS", "Cells failed"))
        self.addOutput(QgsProcessingOutputNumber("RELEASE_VOLUME", "Release volume (m³)"))

    def command(self, parameters, context, out):
        app = shutil.which("slope-stability", path=os.environ.get("GEOHAZ_BIN_DIR", os.environ.get("PATH")))
        if app is None:
            raise QgsProcessingException("slope-stability not found on PATH (package geohaz)")
        dsm = self.parameterAsRasterLayer(parameters, "DSM", context)
        cmd = [app, _file_of(dsm), "--out", out]
        sets = []
        for name, key, _, _, _, _ in NUMBERS:
            sets.append(f"{key}={self.parameterAsDouble(parameters, name, context)!r}")
        depth_raster = self.parameterAsRasterLayer(parameters, "SOIL_DEPTH_RASTER", context)
        if depth_raster is not None:
            sets.append(f'soil.depth_raster={json.dumps(_file_of(depth_raster))}')
        try:
            rain = [float(v) for v in self.parameterAsString(parameters, "RAIN_INTENSITY", context).split(",")
                    if v.strip()]
        except ValueError as e:
            raise QgsProcessingException(f"RAIN_INTENSITY: not a comma-separated list of numbers (m/s): {e}")
        if not rain:
            raise QgsProcessingException("RAIN_INTENSITY: give at least one intensity (m/s)")
        sets.append("rain.intensity=[" + ", ".join(repr(v) for v in rain) + "]")
        duration = self.parameterAsDouble(parameters, "DURATION", context)
        if duration > 0:
            sets.append(f"run.duration={duration!r}")
        sets += [f"{k}={v}" for k, v in split_set(self.parameterAsString(parameters, "SET", context))]
        for kv in sets:
            cmd += ["--set", kv]
        return cmd

    def processAlgorithm(self, parameters, context, feedback):  # noqa: N802
        out = self.parameterAsString(parameters, "OUTPUT", context)
        cmd = self.command(parameters, context, out)
        feedback.pushCommandInfo(" ".join(cmd))
        progress_line = re.compile(r"t = ([0-9.eE+-]+) / ([0-9.eE+-]+) s")
        with tempfile.TemporaryFile(mode="w+", dir=QgsProcessingUtils.tempFolder()) as log:
            proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=log, text=True)
            read = 0
            while True:
                try:
                    code = proc.wait(timeout=0.2)
                except subprocess.TimeoutExpired:
                    code = None
                log.seek(read)
                text = log.read()
                read = log.tell()
                for m in progress_line.finditer(text):
                    t, end = float(m.group(1)), float(m.group(2))
                    if end > 0:
                        feedback.setProgress(min(100.0, 100.0 * t / end))
                if code is not None:
                    break
                if feedback.isCanceled():
                    proc.terminate()
                    proc.wait()
                    feedback.reportError(f"canceled: slope-stability stopped; {out} is incomplete")
                    return {}
            log.seek(0)
            messages = log.read().strip()
        if code != 0:
            raise QgsProcessingException(messages or f"slope-stability exited with {code}")
        feedback.pushInfo(messages.splitlines()[-1] if messages else "slope-stability finished")
        with open(os.path.join(out, "summary.json")) as f:
            s = json.load(f)
        maps = _load_maps(out, MAPS, context, "slope stability")
        release = os.path.join(out, "release.gpkg")
        layer = QgsVectorLayer(release + "|layername=release", "slope stability: release", "ogr")
        if layer.isValid():
            # Failed cells in red over the maps (release.gpkg carries no style of its own).
            layer.setRenderer(QgsSingleSymbolRenderer(QgsFillSymbol.createSimple(
                {"color": "228,26,28,120", "outline_color": "153,0,0,255", "outline_width": "0.2"})))
            context.temporaryLayerStore().addMapLayer(layer)
            context.addLayerToLoadOnCompletion(layer.id(), QgsProcessingContext.LayerDetails(
                "slope stability: release", context.project(), "release"))
        return {"OUTPUT": out, "FS_MIN": os.path.join(out, "fs_min.tif"),
                "FAILURE_TIME": os.path.join(out, "failure_time.tif"), "RELEASE": release, "MAPS": maps,
                "FAILED_CELLS": s["cells"]["failed"], "RELEASE_VOLUME": s["release"]["volume_m3"]}
