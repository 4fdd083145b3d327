#include "geohaz/core/handoff.hpp"

#include <cmath>
#include <cstdlib>
#include <numeric>
#include <stdexcept>

#include "geohaz/core/errors.hpp"
#include "geohaz/core/snapshot.hpp"

namespace geohaz {

double Handoff::total_volume() const noexcept {
  return std::accumulate(volumes.begin(), volumes.end(), 0.0);
}

void write_handoff(const std::filesystem::path& path, const Handoff& h, const std::string& resolved_config) {
  if (h.points.size() != h.volumes.size())
    throw std::invalid_argument("write_handoff: " + std::to_string(h.points.size()) + " points but " +
                                std::to_string(h.volumes.size()) + " volumes");
  SnapshotWriter w(path, kHandoffModel, 2, resolved_config);
  w.set_attribute("crs_wkt", h.crs_wkt);
  w.set_attribute("total_volume", h.total_volume());
  w.set_attribute("source", h.source);
  w.set_attribute("bulking_factor", h.bulking_factor);
  const FieldView views[] = {{"position", "m", ScalarType::Float64, h.points.data(), h.points.size(), 2, 1},
                             {"volume", "m^3", ScalarType::Float64, h.volumes.data(), h.volumes.size(), 1, 1}};
  w.write(h.time, h.step, views);
}

Handoff read_handoff(const std::filesystem::path& path) {
  const std::string file = path.string();
  SnapshotReader rd(path);
  if (rd.model() != kHandoffModel)
    throw InputError("not a hand-off file: its model attribute is '" + rd.model() + "', expected '" + kHandoffModel +
                         "' (sph-slope writes release.h5 for a section scenario)",
                     file, "model");
  if (rd.snapshot_count() == 0) throw InputError("the hand-off file holds no snapshot", file);
  const std::size_t k = rd.snapshot_count() - 1;
  for (const char* f : {"position", "volume"})
    if (!rd.has_field(k, f))
      throw InputError("the hand-off file lacks the field (needs 'position' (m) and 'volume' (m^3))", file, f);
  const FieldData pos = rd.read(k, "position"), vol = rd.read(k, "volume");
  if (pos.components() != 2) throw InputError("'position' must hold 2D map points (x, y)", file, "position");
  if (vol.components() != 1 || vol.count != pos.count)
    throw InputError("'volume' must hold one value per point (" + std::to_string(pos.count) + " points, " +
                         std::to_string(vol.count) + " volumes)",
                     file, "volume");
  Handoff h;
  h.points.resize(pos.count);
  for (std::size_t i = 0; i < pos.count; ++i) {
    h.points[i] = Vec2(pos.values[2 * i], pos.values[2 * i + 1]);
    if (!h.points[i].allFinite())
      throw InputError("point " + std::to_string(i) + " has a non-finite position", file, "position");
  }
  h.volumes = vol.values;
  for (std::size_t i = 0; i < h.volumes.size(); ++i)
    if (!(h.volumes[i] >= 0.0) || !std::isfinite(h.volumes[i]))
      throw InputError("point " + std::to_string(i) + " has a negative or non-finite volume", file, "volume",
                       std::to_string(h.volumes[i]));
  const double total = h.total_volume();
  if (!(total > 0.0))
    throw InputError("the hand-off file holds no volume (no failed material: nothing to run out)", file, "volume",
                     std::to_string(total));
  const std::string attr = rd.attribute("total_volume");
  if (!attr.empty()) {
    const double tv = std::strtod(attr.c_str(), nullptr);
    if (!(std::abs(tv - total) <= 1e-9 * std::max(1.0, std::abs(tv))))
      throw InputError("the total_volume attribute differs from the sum of the point volumes (" +
                           std::to_string(total) + " m^3): the file is inconsistent",
                       file, "total_volume", attr);
  }
  h.crs_wkt = rd.attribute("crs_wkt");
  h.source = rd.attribute("source");
  const std::string bulk = rd.attribute("bulking_factor");
  h.bulking_factor = bulk.empty() ? 1.0 : std::strtod(bulk.c_str(), nullptr);
  h.time = rd.time(k);
  h.step = rd.step(k);
  return h;
}

}  // namespace geohaz
