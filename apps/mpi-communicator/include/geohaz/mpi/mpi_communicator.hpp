#pragma once
/// \file mpi_communicator.hpp
/// Open MPI behind core's Communicator (geohaz/core/communicator.hpp), on the ranks of an app's MPI
/// session (session.hpp). Only apps and MPI tests include this header; the model libraries see the
/// Communicator interface.

#include <memory>

#include "geohaz/core/communicator.hpp"
#include "geohaz/mpi/session.hpp"

namespace geohaz::mpi {

/// The world communicator of an active session (every rank of the job); null when the process was
/// not started by mpirun.
std::shared_ptr<const Communicator> world_communicator(const Session& session);

}  // namespace geohaz::mpi
