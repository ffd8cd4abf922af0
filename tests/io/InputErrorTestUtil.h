#pragma once
// Test helper shared by the io tests: run a call that must fail with a located InputError.
#include <io/InputError.h>

#include <gtest/gtest.h>

#include <functional>

namespace io::test {

/// Runs f, expects an InputError and returns it (an empty one, after a test failure, if none).
inline InputError expectInputError(const std::function<void()>& f) {
    try {
        f();
    } catch (const InputError& e) {
        return e;
    }
    ADD_FAILURE() << "no InputError thrown";
    return InputError("", 0, "", "");
}

}  // namespace io::test
