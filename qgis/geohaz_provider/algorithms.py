"""The geohaz Processing algorithms. debris_runout, ensemble and calibrate (calibration.py) run in the
QGIS process through the Python package geohaz (the apps' own library code: same config keys, checks
and outputs); slope_stability (stability.py) and report run the apps. Progress goes to the
Processing feedback; Cancel stops a run at its next step (the progress callback raises, and the run
ends without writing its maps)."""
import os
import shutil
import subprocess
import warnings

from qgis.core import (QgsProcessing, QgsProcessingAlgorithm, QgsProcessingContext, QgsProcessingException,
                       QgsProcessingOutputFolder, QgsProcessingOutputMultipleLayers, QgsProcessingParameterEnum,
                       QgsProcessingParameterFile, QgsProcessingParameterFolderDestination,
                       QgsProcessingParameterNumber, QgsProcessingParameterRasterLayer,
                       QgsProcessingParameterString, QgsProcessingParameterVectorLayer, QgsRasterLayer)

FRICTION_LAWS = ["manning", "voellmy", "coulomb"]  # model.friction (libs/runout basal_friction.hpp)


class _Canceled(Exception):
    pass


def _geohaz():
    try:
        import geohaz
    except ImportError as e:
        raise QgsProcessingException(
            "the Python package geohaz is not importable from QGIS's Python: install python3-geohaz, or "
            f"pip install it into the Python QGIS uses (docs/qgis.md) ({e})")
    return geohaz


def _load_maps(folder, names, context, group):
    """Load the GeoTIFFs of an output folder when the algorithm completes; QGIS applies the .qml
    style the app wrote beside each one (the layer's default style)."""
    loaded = []
    for name in names:
        path = os.path.join(folder, name + ".tif")
        if not os.path.isfile(path):
            continue
        layer = QgsRasterLayer(path, f"{group}: {name}")
        if not layer.isValid():
            continue
        layer.loadDefaultStyle()
        context.temporaryLayerStore().addMapLayer(layer)
        context.addLayerToLoadOnCompletion(layer.id(), QgsProcessingContext.LayerDetails(
            f"{group}: {name}", context.project(), name))
        loaded.append(path)
    return loaded


def member_progress(feedback):
    """The progress callback of geohaz.ensemble.run and geohaz.calibrate.run for a Processing
    feedback: the bar follows members done plus the simulated time of the member running; Cancel
    raises _Canceled, which stops the run at its next reported step."""
    def progress(p):
        if feedback.isCanceled():
            raise _Canceled()
        planned = max(1, p.get("members_planned", 1))
        if p["phase"] == "member_finished":
            feedback.setProgress(min(100.0, 100.0 * p["members_done"] / planned))
            if not p["ok"]:
                feedback.pushWarning(f"member {p['member']} failed (see members.csv)")
        elif p.get("duration"):
            frac = min(1.0, p["time"] / p["duration"])
            feedback.setProgress(min(100.0, 100.0 * (p["members_done"] + frac) / planned))
    return progress


class _Base(QgsProcessingAlgorithm):
    def group(self):
        return "Landslides"

    def groupId(self):  # noqa: N802
        return "landslides"

    def createInstance(self):  # noqa: N802
        return type(self)()

    def flags(self):
        # In-process runs release the GIL; QGIS must not run them on a thread of its own while the
        # project's layers are read by GDAL from the same files.
        return super().flags() | QgsProcessingAlgorithm.FlagNoThreading


class DebrisRunoutAlgorithm(_Base):
    """geohaz:debris_runout, the debris-runout app's main inputs as Processing parameters."""

    MAPS = ["max_depth", "max_speed", "max_pressure", "deposit", "arrival_time", "intensity"]

    def name(self):
        return "debris_runout"

    def displayName(self):  # noqa: N802
        return "Debris runout"

    def shortHelpString(self):  # noqa: N802
        return ("Depth-averaged particle debris flow over a DSM (debris-runout, docs/runout.md): hazard maps "
                "max_depth (m), max_speed (m/s), max_pressure (Pa), deposit (m), arrival_time (s), intensity, "
                "written as GeoTIFF with QGIS styles into the output folder and loaded. Units SI.")

    def initAlgorithm(self, config=None):  # noqa: N802
        P = self.addParameter
        P(QgsProcessingParameterRasterLayer("DSM", "DSM (elevation, m; projected CRS)"))
        P(QgsProcessingParameterVectorLayer("RELEASE", "Release polygons", [QgsProcessing.TypeVectorPolygon],
                                            optional=True))
        P(QgsProcessingParameterRasterLayer("RELEASE_RASTER", "Release thickness raster (m), instead of polygons",
                                            optional=True))
        P(QgsProcessingParameterNumber("RELEASE_DEPTH", "Release depth of the polygons (m, slope-normal; 0: their attribute thickness)",
                                       QgsProcessingParameterNumber.Double, 1.0, optional=True, minValue=0.0))
        P(QgsProcessingParameterVectorLayer("BARRIERS", "Barriers (lines or polygons)", optional=True))
        P(QgsProcessingParameterVectorLayer("ZONES", "Friction zones (attributes n, icr, mu, xi)",
                                            [QgsProcessing.TypeVectorPolygon], optional=True))
        P(QgsProcessingParameterVectorLayer("FOREST", "Forest (attributes stem_density, stem_diameter)",
                                            [QgsProcessing.TypeVectorPolygon], optional=True))
        P(QgsProcessingParameterEnum("FRICTION", "Basal friction law", FRICTION_LAWS, defaultValue=0))
        P(QgsProcessingParameterNumber("N", "Manning n (s/m^(1/3))", QgsProcessingParameterNumber.Double, 0.06,
                                       minValue=0.005, maxValue=0.5))
        P(QgsProcessingParameterNumber("ICR", "Critical slope i_cr (1, manning)", QgsProcessingParameterNumber.Double,
                                       0.15, minValue=0.0))
        P(QgsProcessingParameterNumber("MU", "Coulomb friction mu (1, voellmy, coulomb)",
                                       QgsProcessingParameterNumber.Double, 0.2, minValue=0.0))
        P(QgsProcessingParameterNumber("XI", "Turbulent friction xi (m/s², voellmy)",
                                       QgsProcessingParameterNumber.Double, 500.0, minValue=0.0))
        P(QgsProcessingParameterNumber("D0", "Particle spacing d0 (m); larger is coarser and faster",
                                       QgsProcessingParameterNumber.Double, 0.0, optional=True, minValue=0.0))
        P(QgsProcessingParameterNumber("H0", "Reference depth h0 (m)", QgsProcessingParameterNumber.Double, 0.0,
                                       optional=True, minValue=0.0))
        P(QgsProcessingParameterNumber("DURATION", "Simulated time (s)", QgsProcessingParameterNumber.Double, 600.0,
                                       minValue=0.0))
        P(QgsProcessingParameterString("SET", "Other config keys (key=value; separated by ';')", optional=True))
        P(QgsProcessingParameterFolderDestination("OUTPUT", "Output folder"))
        self.addOutput(QgsProcessingOutputMultipleLayers("MAPS", "Hazard maps"))

    def processAlgorithm(self, parameters, context, feedback):  # noqa: N802
        geohaz = _geohaz()
        dsm = self.parameterAsRasterLayer(parameters, "DSM", context)
        release = self.parameterAsVectorLayer(parameters, "RELEASE", context)
        release_raster = self.parameterAsRasterLayer(parameters, "RELEASE_RASTER", context)
        if (release is None) == (release_raster is None):
            raise QgsProcessingException("give either release polygons or a release thickness raster")
        out = self.parameterAsString(parameters, "OUTPUT", context)
        overrides = {}
        for key, param in (("barriers.file", "BARRIERS"), ("zones.file", "ZONES"), ("forest.file", "FOREST")):
            layer = self.parameterAsVectorLayer(parameters, param, context)
            if layer is not None:
                overrides[key] = _file_of(layer)
        friction = FRICTION_LAWS[self.parameterAsEnum(parameters, "FRICTION", context)]
        flags = {"friction": friction, "duration": self.parameterAsDouble(parameters, "DURATION", context)}
        if friction == "manning":
            flags.update(n=self.parameterAsDouble(parameters, "N", context),
                         icr=self.parameterAsDouble(parameters, "ICR", context))
        else:
            flags["mu"] = self.parameterAsDouble(parameters, "MU", context)
            if friction == "voellmy":
                flags["xi"] = self.parameterAsDouble(parameters, "XI", context)
        for flag, param in (("d0", "D0"), ("h0", "H0"), ("release_depth", "RELEASE_DEPTH")):
            v = self.parameterAsDouble(parameters, param, context)
            if v > 0 and (flag != "release_depth" or release is not None):
                flags[flag] = v
        extra = [kv.strip() for kv in (self.parameterAsString(parameters, "SET", context) or "").split(";")
                 if kv.strip()]
        overrides = [f"{k}={geohaz._overrides.toml_value(v)}" for k, v in overrides.items()] + extra

        def progress(p):
            if feedback.isCanceled():
                raise _Canceled()
            if p.get("duration"):
                feedback.setProgress(min(100.0, 100.0 * p["time"] / p["duration"]))

        feedback.pushInfo(f"debris-runout {geohaz.__version__}: {flags}, {overrides}")
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always", RuntimeWarning)
                r = geohaz.runout.run(_file_of(dsm), release=_file_of(release or release_raster), set=overrides,
                                      out=out, progress=progress, progress_every=20, particles=False, **flags)
            for w in caught:
                feedback.pushWarning(str(w.message))
        except _Canceled:
            feedback.reportError("canceled: nothing written")
            return {}
        except geohaz.InputError as e:
            raise QgsProcessingException(f"input error: {e}")
        s = r["summary"]
        feedback.pushInfo(f"{s['ended_by']} at {s['simulated_time_s']:.0f} s; run-out "
                          f"{s['runout_length_along_path_m']:.0f} m; max speed {s['max_speed_m_per_s']:.1f} m/s")
        return {"OUTPUT": out, "MAPS": _load_maps(out, self.MAPS, context, "debris runout")}


class EnsembleAlgorithm(_Base):
    """geohaz:ensemble, a geohaz-ensemble config run in this process on one rank."""

    def name(self):
        return "ensemble"

    def displayName(self):  # noqa: N802
        return "Debris runout ensemble"

    def shortHelpString(self):  # noqa: N802
        return ("An ensemble of debris-runout runs with sampled parameters (geohaz-ensemble, docs/ensemble.md) "
                "on one process: probability, mean and percentile maps in the output folder, loaded with styles. "
                "Progress follows the members; Cancel keeps the finished members in the folder (running again "
                "into it resumes them). For many members use the MPI app geohaz-ensemble (package geohaz-ensemble).")

    def initAlgorithm(self, config=None):  # noqa: N802
        self.addParameter(QgsProcessingParameterFile("CONFIG", "Ensemble config (TOML)", extension="toml"))
        self.addParameter(QgsProcessingParameterNumber("MEMBERS", "Members (0: as in the config)",
                                                       QgsProcessingParameterNumber.Integer, 0, minValue=0))
        self.addParameter(QgsProcessingParameterFolderDestination("OUTPUT", "Output folder"))
        self.addOutput(QgsProcessingOutputMultipleLayers("MAPS", "Ensemble maps"))

    def processAlgorithm(self, parameters, context, feedback):  # noqa: N802
        geohaz = _geohaz()
        members = self.parameterAsInt(parameters, "MEMBERS", context)
        out = self.parameterAsString(parameters, "OUTPUT", context)
        overrides = {"ensemble.members": members} if members > 0 else None
        try:
            r = geohaz.ensemble.run(self.parameterAsFile(parameters, "CONFIG", context), set=overrides, out=out,
                                    progress=member_progress(feedback), progress_every=20)
        except _Canceled:
            feedback.reportError("canceled: the finished members stay in the output folder (a rerun resumes "
                                 "them); no maps written")
            return {}
        except geohaz.InputError as e:
            raise QgsProcessingException(f"input error: {e}")
        feedback.pushInfo(f"{r['summary'].get('succeeded')} members finished")
        return {"OUTPUT": out, "MAPS": _load_maps(out, sorted(r["maps"]), context, "ensemble")}


class ReportAlgorithm(_Base):
    """geohaz:report, the geohaz-report app on a results folder."""

    def name(self):
        return "report"

    def displayName(self):  # noqa: N802
        return "Report page"

    def shortHelpString(self):  # noqa: N802
        return "One HTML page from the output folders of geohaz runs (geohaz-report): report.html in the folder."

    def initAlgorithm(self, config=None):  # noqa: N802
        self.addParameter(QgsProcessingParameterFile("RESULTS", "Results folder (one sub-folder per run)",
                                                     behavior=QgsProcessingParameterFile.Folder))
        self.addParameter(QgsProcessingParameterString("TITLE", "Title", optional=True))
        self.addOutput(QgsProcessingOutputFolder("OUTPUT", "Results folder with report.html"))

    def processAlgorithm(self, parameters, context, feedback):  # noqa: N802
        app = shutil.which("geohaz-report", path=os.environ.get("GEOHAZ_BIN_DIR", os.environ.get("PATH")))
        if app is None:
            raise QgsProcessingException("geohaz-report not found on PATH (package geohaz)")
        results = self.parameterAsFile(parameters, "RESULTS", context)
        cmd = [app, "--results", results]
        title = self.parameterAsString(parameters, "TITLE", context)
        if title:
            cmd += ["--title", title]
        proc = subprocess.run(cmd, capture_output=True, text=True)
        if proc.returncode != 0:
            raise QgsProcessingException(proc.stderr.strip() or f"geohaz-report exited with {proc.returncode}")
        feedback.pushInfo(proc.stdout.strip())
        return {"OUTPUT": results}


def _file_of(layer):
    """The file behind a layer (GDAL/OGR source without the '|layername=' part)."""
    return layer.source().split("|")[0]
