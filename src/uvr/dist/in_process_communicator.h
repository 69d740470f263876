// SPDX-License-Identifier: MIT
#pragma once

#include <functional>
#include <memory>

#include "uvr/dist/communicator.h"

namespace uvr {

/// A group of ranks that are threads of this process: each rank runs the same body with its own
/// Communicator, as MPI's ranks run one program (tests, and several GPUs of one host).
class InProcessGroup {
public:
    /// Runs body on `ranks` threads (rank 0 on the calling thread) and returns when every rank
    /// has ended. A rank whose body throws stops the group: ranks waiting in a collective or a
    /// receive (or entering one later) throw an Internal error "rank R failed: ...", so run()
    /// always returns; it then rethrows the lowest rank's own exception (not one a rank threw
    /// because another failed).
    static void run(int ranks, const std::function<void(Communicator&)>& body);
};

/// A communicator of this rank alone (size 1): collectives hand back the rank's own bytes,
/// send() queues a message that receive(0) returns; no threads.
std::unique_ptr<Communicator> selfCommunicator();

}  // namespace uvr
