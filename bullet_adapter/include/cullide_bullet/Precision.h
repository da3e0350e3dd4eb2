// Guard against mixing float and double Bullet builds: the adapter library is compiled against one precision
// (Debian's libBullet*.so: float), and an application compiled with BT_USE_DOUBLE_PRECISION (or the reverse) would
// otherwise link fine and run with silently wrong class layouts.
#pragma once

#include <LinearMath/btScalar.h>

#include <stdexcept>
#include <string>

namespace cullide::detail {

/// sizeof(btScalar) the cullide_bullet library was compiled with (4: float, 8: double).
int bulletScalarSizeOfLibrary() noexcept;

/// Evaluated in the application's translation unit (inline), so it sees the application's btScalar.
inline void requireMatchingBulletPrecision() {
    const int library = bulletScalarSizeOfLibrary();
    if (library != static_cast<int>(sizeof(btScalar))) {
        const auto name = [](int size) { return size == 8 ? std::string("double") : std::string("float"); };
        throw std::runtime_error(
            "cullide_bullet: Bullet precision mismatch: the library was built with btScalar = " + name(library) +
            " but this program is compiled with btScalar = " + name(static_cast<int>(sizeof(btScalar))) +
            ". Compile with the same BT_USE_DOUBLE_PRECISION setting as cullide_bullet and link the matching "
            "Bullet libraries (libBullet*.so for float, libBullet*-float64.so for double).");
    }
}

/// Tag returned by the check; the public constructors delegate through it so the check runs first.
struct PrecisionChecked {};
inline PrecisionChecked checkBulletPrecision() {
    requireMatchingBulletPrecision();
    return PrecisionChecked{};
}

}  // namespace cullide::detail
