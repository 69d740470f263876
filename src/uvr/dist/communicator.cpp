// SPDX-License-Identifier: MIT
#include "uvr/dist/communicator.h"

#include <string>

#include "uvr/core/error.h"

namespace uvr {

namespace {

/// The kind and message of a failure (an exception that is not a uvr::Error is Internal).
std::pair<ErrorKind, std::string> describe(const std::exception_ptr& failure) {
    try {
        std::rethrow_exception(failure);
    } catch (const Error& e) {
        return {e.kind(), e.what()};
    } catch (const std::exception& e) {
        return {ErrorKind::Internal, e.what()};
    } catch (...) {
        return {ErrorKind::Internal, "an exception that is not a std::exception"};
    }
}

}  // namespace

void Communicator::agree(std::exception_ptr failure) {
    // Each rank's report: nothing when it did not fail, else its kind's byte and its message.
    std::vector<std::byte> report;
    if (failure) {
        auto [kind, message] = describe(failure);
        report.reserve(1 + message.size());
        report.push_back(std::byte(static_cast<unsigned char>(kind)));
        for (char c : message) report.push_back(std::byte(static_cast<unsigned char>(c)));
    }
    std::vector<std::vector<std::byte>> reports = allGather(report);
    for (std::size_t r = 0; r < reports.size(); ++r) {
        const std::vector<std::byte>& bytes = reports[r];
        if (bytes.empty()) continue;
        auto kind = static_cast<ErrorKind>(std::to_integer<unsigned char>(bytes[0]));
        if (kind > ErrorKind::Internal) kind = ErrorKind::Internal;
        std::string message(reinterpret_cast<const char*>(bytes.data()) + 1, bytes.size() - 1);
        throwError(kind, "", "rank " + std::to_string(r) + ": " + message);
    }
}

namespace detail {

void throwBadValueBytes(std::size_t bytes, std::size_t size) {
    throwError(ErrorKind::Internal, "",
               "a message of " + std::to_string(bytes) + " bytes does not hold values of " +
                   std::to_string(size) + " bytes each");
}

void checkRankArgument(const Communicator& comm, int rank, const char* call, const char* what) {
    if (rank < 0 || rank >= comm.size())
        throwError(ErrorKind::Argument, "",
                   std::string(call) + ": " + what + " " + std::to_string(rank) +
                       " is not a rank of the group (it has " + std::to_string(comm.size()) +
                       " ranks)");
}

}  // namespace detail

}  // namespace uvr
