// SPDX-License-Identifier: MIT
// What uvr's HDF5 code shares (built with HDF5 only): HDF5's error stack made quiet and read back
// into messages, and identifiers closed when they go out of scope.
#pragma once

#include <hdf5.h>

#include <string>

namespace uvr {

/// Turns off HDF5's printing of its error stack (its failures become uvr::Errors).
inline void quietHdf5() {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
}

/// The innermost message of HDF5's error stack (what failed at the bottom), then clears it.
inline std::string hdf5Message() {
    std::string message;
    H5Ewalk2(
        H5E_DEFAULT, H5E_WALK_UPWARD,
        [](unsigned n, const H5E_error2_t* e, void* data) -> herr_t {
            if (n == 0 && e->desc) *static_cast<std::string*>(data) = e->desc;
            return 0;
        },
        &message);
    H5Eclear2(H5E_DEFAULT);
    return message.empty() ? std::string() : " (HDF5: " + message + ")";
}

/// An HDF5 identifier closed by its close function when it goes out of scope.
class H5Handle {
public:
    H5Handle() = default;
    H5Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
    H5Handle(H5Handle&& o) noexcept : id_(o.id_), close_(o.close_) { o.id_ = -1; }
    H5Handle& operator=(H5Handle&& o) noexcept {
        if (this != &o) {
            reset();
            id_ = o.id_;
            close_ = o.close_;
            o.id_ = -1;
        }
        return *this;
    }
    H5Handle(const H5Handle&) = delete;
    H5Handle& operator=(const H5Handle&) = delete;
    ~H5Handle() { reset(); }

    hid_t get() const { return id_; }
    void reset() {
        if (id_ >= 0 && close_) close_(id_);
        id_ = -1;
    }

private:
    hid_t id_ = -1;
    herr_t (*close_)(hid_t) = nullptr;
};

}  // namespace uvr
