"""geohaz:calibrate, the back-analysis of debris-runout against an observed event (geohaz-calibrate,
docs/calibration.md) in the QGIS process through geohaz.calibrate.run. The base case and the
calibration config are written as TOML into a temporary folder of Processing from the inputs; every
path in them is absolute."""
import os
import tempfile

from qgis.core import (QgsProcessing, QgsProcessingException, QgsProcessingOutputFile, QgsProcessingOutputNumber,
                       QgsProcessingOutputRasterLayer, QgsProcessingOutputString, QgsProcessingParameterEnum,
                       QgsProcessingParameterFolderDestination, QgsProcessingParameterNumber,
                       QgsProcessingParameterRange, QgsProcessingParameterRasterLayer, QgsProcessingParameterString,
                       QgsProcessingParameterVectorLayer, QgsProcessingUtils)

from .algorithms import FRICTION_LAWS, _Base, _Canceled, _file_of, _geohaz, _load_maps, member_progress

# The searched keys of each law: (parameter, config key, description, default bounds, scale).
SEARCHED = {
    "manning": [("N_RANGE", "model.n", "Manning n bounds (s/m^(1/3)), searched on a log scale", "0.03,0.12", "log"),
                ("ICR_RANGE", "model.icr", "Critical slope i_cr bounds (1)", "0.08,0.3", "linear")],
    "voellmy": [("MU_RANGE", "model.mu", "Coulomb friction mu bounds (1)", "0.05,0.4", "linear"),
                ("XI_RANGE", "model.xi", "Turbulent friction xi bounds (m/s², searched on a log scale)", "100,2000",
                 "log")],
    "coulomb": [("MU_RANGE", "model.mu", "Coulomb friction mu bounds (1)", "0.05,0.4", "linear")],
}
# Prefixes of keys that belong to the calibration config; any other SET key goes to the base case.
CALIBRATION_SECTIONS = ("calibration.", "observation.", "score.")


def toml_text(sections):
    """{section: [(key, TOML value text), ...]} as TOML (sections in order)."""
    lines = []
    for section, items in sections.items():
        lines.append(f"[{section}]")
        lines += [f"{k} = {v}" for k, v in items]
        lines.append("")
    return "\n".join(lines)


def split_set(text):
    """`a.b=v; c.d=w` as [(a.b, v), ...] (values as TOML text)."""
    pairs = []
    for kv in (text or "").split(";"):
        if not kv.strip():
            continue
        if "=" not in kv:
            raise QgsProcessingException(f"SET: '{kv.strip()}' is not key=value")
        k, v = kv.split("=", 1)
        pairs.append((k.strip(), v.strip()))
    return pairs


class CalibrateAlgorithm(_Base):
    """geohaz:calibrate: DSM, release, observed footprint and thalweg layers, the friction law and the
    bounds of its parameters as Processing inputs."""

    def name(self):
        return "calibrate"

    def displayName(self):  # noqa: N802
        return "Debris runout calibration (back-analysis)"

    def shortHelpString(self):  # noqa: N802
        return ("Fits the friction parameters of debris-runout to an observed event (geohaz-calibrate, "
                "docs/calibration.md): a Latin hypercube and Morris trajectories over the bounds, then local "
                "searches (NLopt), each member a debris-runout run scored against the observed footprint "
                "(Tversky index), the run-out along the thalweg and, if given, the deposit. Outputs: best.toml "
                "(the base case with the fitted values), the comparison map of the best member (1 true positive, "
                "2 false positive, 3 false negative; loaded with its style), members.csv, acceptable.csv, "
                "sensitivity.csv. Progress follows the members; Cancel keeps the finished ones (running again "
                "into the same folder resumes them). Units SI.")

    def initAlgorithm(self, config=None):  # noqa: N802
        P = self.addParameter
        Dbl, Int = QgsProcessingParameterNumber.Double, QgsProcessingParameterNumber.Integer
        P(QgsProcessingParameterRasterLayer("DSM", "DSM (elevation, m; projected CRS)"))
        P(QgsProcessingParameterVectorLayer("RELEASE", "Release polygons", [QgsProcessing.TypeVectorPolygon],
                                            optional=True))
        P(QgsProcessingParameterRasterLayer("RELEASE_RASTER", "Release thickness raster (m), instead of polygons",
                                            optional=True))
        P(QgsProcessingParameterNumber("RELEASE_DEPTH", "Release depth of the polygons (m, slope-normal; 0: their attribute thickness)", Dbl, 1.0,
                                       optional=True, minValue=0.0))
        P(QgsProcessingParameterVectorLayer("OBSERVED", "Observed footprint (polygons)",
                                            [QgsProcessing.TypeVectorPolygon], optional=True))
        P(QgsProcessingParameterRasterLayer("OBSERVED_RASTER", "Observed footprint raster on the DSM grid, instead "
                                            "of polygons (affected where the value exceeds the threshold)",
                                            optional=True))
        P(QgsProcessingParameterNumber("FOOTPRINT_THRESHOLD", "Footprint raster threshold (its unit, e.g. m)", Dbl,
                                       0.0, optional=True))
        P(QgsProcessingParameterVectorLayer("THALWEG", "Thalweg: the flow path as a line, from the release down",
                                            [QgsProcessing.TypeVectorLine]))
        P(QgsProcessingParameterRasterLayer("DEPOSIT", "Observed deposit depth raster on the DSM grid (m, vertical)",
                                            optional=True))
        P(QgsProcessingParameterEnum("FRICTION", "Basal friction law", FRICTION_LAWS, defaultValue=0))
        seen = set()
        for law in FRICTION_LAWS:
            for param, _, desc, default, _ in SEARCHED[law]:
                if param not in seen:
                    seen.add(param)
                    # Optional: only the chosen law's bounds matter (qgis_process asks for every
                    # mandatory parameter); a missing range takes its default.
                    P(QgsProcessingParameterRange(param, desc, QgsProcessingParameterNumber.Double, default,
                                                  optional=True))
        P(QgsProcessingParameterNumber("D0", "Particle spacing d0 (m); 0 keeps the default", Dbl, 0.0, optional=True,
                                       minValue=0.0))
        P(QgsProcessingParameterNumber("H0", "Reference depth h0 (m); 0 keeps the default", Dbl, 0.0, optional=True,
                                       minValue=0.0))
        P(QgsProcessingParameterNumber("DURATION", "Simulated time of each member (s)", Dbl, 600.0, minValue=0.0))
        P(QgsProcessingParameterNumber("GLOBAL_MEMBERS", "Members of the space-filling design (1)", Int, 12,
                                       minValue=1))
        P(QgsProcessingParameterNumber("MORRIS_TRAJECTORIES", "Morris trajectories for the sensitivity (1; 0: none)",
                                       Int, 2, minValue=0))
        P(QgsProcessingParameterNumber("LOCAL_STARTS", "Local searches (1)", Int, 1, minValue=0))
        P(QgsProcessingParameterNumber("LOCAL_EVALUATIONS", "Members per local search at most (1)", Int, 16,
                                       minValue=1))
        P(QgsProcessingParameterNumber("SEED", "Seed of the design (1)", Int, 1, minValue=0))
        P(QgsProcessingParameterString("SET", "Other config keys (key=value; separated by ';'): calibration.*, "
                                       "observation.*, score.* go to the calibration, any other key to the base case",
                                       optional=True))
        P(QgsProcessingParameterFolderDestination("OUTPUT", "Output folder"))
        self.addOutput(QgsProcessingOutputFile("BEST_CONFIG", "best.toml: the base case with the fitted values"))
        self.addOutput(QgsProcessingOutputRasterLayer("COMPARISON", "Comparison of the best member with the event"))
        self.addOutput(QgsProcessingOutputString("BEST", "Fitted values (key=value; ...)"))
        self.addOutput(QgsProcessingOutputNumber("SCORE", "Score of the best member (0: perfect)"))

    def configs(self, parameters, context, folder):
        """Write base.toml and calibrate.toml into `folder` from the inputs; returns the calibration's
        path and its overrides."""
        num = lambda p: self.parameterAsDouble(parameters, p, context)  # noqa: E731
        integer = lambda p: self.parameterAsInt(parameters, p, context)  # noqa: E731
        q = lambda path: _geohaz()._overrides.toml_value(path)  # noqa: E731 (a TOML string)
        dsm = self.parameterAsRasterLayer(parameters, "DSM", context)
        release = self.parameterAsVectorLayer(parameters, "RELEASE", context)
        release_raster = self.parameterAsRasterLayer(parameters, "RELEASE_RASTER", context)
        if (release is None) == (release_raster is None):
            raise QgsProcessingException("give either release polygons or a release thickness raster")
        observed = self.parameterAsVectorLayer(parameters, "OBSERVED", context)
        observed_raster = self.parameterAsRasterLayer(parameters, "OBSERVED_RASTER", context)
        if (observed is None) == (observed_raster is None):
            raise QgsProcessingException("give either observed footprint polygons or a footprint raster")
        law = FRICTION_LAWS[self.parameterAsEnum(parameters, "FRICTION", context)]
        searched = []
        model = [("friction", q(law))]
        for param, key, _, default, scale in SEARCHED[law]:
            bounds = self.parameterAsRange(parameters, param, context) or [float(v) for v in default.split(",")]
            if len(bounds) != 2:
                raise QgsProcessingException(f"{param}: give two numbers min,max ({key})")
            lo, hi = bounds
            if not 0.0 < lo < hi:
                raise QgsProcessingException(f"{param}: bounds {lo}, {hi} must satisfy 0 < min < max ({key})")
            searched.append((key, lo, hi, scale))
            # The base value, inside the bounds (each member overrides it).
            model.append((key.split(".")[1], repr((lo * hi) ** 0.5 if scale == "log" else 0.5 * (lo + hi))))
        for flag in ("D0", "H0"):
            if num(flag) > 0:
                model.append((flag.lower(), repr(num(flag))))
        rel = [("file", q(_file_of(release or release_raster)))]
        if release is not None:
            rel.append(("depth", repr(num("RELEASE_DEPTH"))))
        base = {"terrain": [("dsm", q(_file_of(dsm)))], "release": rel, "model": model,
                "run": [("duration", repr(num("DURATION")))]}
        calibration_set = []
        for k, v in split_set(self.parameterAsString(parameters, "SET", context)):
            if k.startswith(CALIBRATION_SECTIONS):
                calibration_set.append(f"{k}={v}")
            else:
                section, _, key = k.rpartition(".")
                if not section:
                    raise QgsProcessingException(f"SET: '{k}' is not a section.key")
                base.setdefault(section, []).append((key, v))
        base_path = os.path.join(folder, "base.toml")
        with open(base_path, "w") as f:
            f.write(toml_text(base))
        obs = [("thalweg", q(_file_of(self.parameterAsVectorLayer(parameters, "THALWEG", context))))]
        if observed is not None:
            obs.append(("footprint", q(_file_of(observed))))
        else:
            obs += [("footprint", q(_file_of(observed_raster))), ("footprint_threshold", repr(num("FOOTPRINT_THRESHOLD")))]
        deposit = self.parameterAsRasterLayer(parameters, "DEPOSIT", context)
        if deposit is not None:
            obs.append(("deposit", q(_file_of(deposit))))
        cal = [("base", q(base_path)), ("seed", str(integer("SEED"))), ("global_members", str(integer("GLOBAL_MEMBERS"))),
               ("morris_trajectories", str(integer("MORRIS_TRAJECTORIES"))),
               ("local_starts", str(integer("LOCAL_STARTS"))), ("local_evaluations", str(integer("LOCAL_EVALUATIONS"))),
               ("local_algorithm", q("bobyqa" if len(searched) >= 2 else "sbplx"))]
        text = toml_text({"calibration": cal})
        for key, lo, hi, scale in searched:
            text += f'[[calibration.parameter]]\nkey = "{key}"\nmin = {lo!r}\nmax = {hi!r}\nscale = "{scale}"\n\n'
        text += toml_text({"observation": obs})
        cal_path = os.path.join(folder, "calibrate.toml")
        with open(cal_path, "w") as f:
            f.write(text)
        return cal_path, calibration_set

    def processAlgorithm(self, parameters, context, feedback):  # noqa: N802
        geohaz = _geohaz()
        out = self.parameterAsString(parameters, "OUTPUT", context)
        folder = tempfile.mkdtemp(prefix="geohaz-calibrate-", dir=QgsProcessingUtils.tempFolder())
        config, overrides = self.configs(parameters, context, folder)
        feedback.pushInfo(f"geohaz-calibrate {geohaz.__version__}: {config}, {overrides}")
        try:
            r = geohaz.calibrate.run(config, set=overrides, out=out, progress=member_progress(feedback),
                                     progress_every=20)
        except _Canceled:
            feedback.reportError("canceled: the finished members stay in the output folder (a rerun resumes "
                                 "them); no outputs written")
            return {}
        except geohaz.InputError as e:
            raise QgsProcessingException(f"input error: {e}")
        s = r["summary"]
        best = "; ".join(f"{k}={v:.6g}" for k, v in r["best"].items())
        score = s["best"]["misfit"]["score"]
        feedback.pushInfo(f"best member {s['best']['member']}: {best}, score {score:.4g} "
                          f"(Tversky {s['best']['misfit']['tversky']:.4g})")
        maps = _load_maps(out, ["comparison"], context, "calibration")
        return {"OUTPUT": out, "BEST_CONFIG": os.path.join(out, "best.toml"), "COMPARISON": maps[0] if maps else None,
                "BEST": best, "SCORE": score}
