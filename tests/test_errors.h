// Checking the errors that bad input raises, in tests.
#pragma once

#include <initializer_list>
#include <string>

#include <gtest/gtest.h>

#include "deltagi/error.h"

namespace deltagi::test {

// The message of the InputError that `action` throws; a test failure (and "") when it throws none.
template <typename Action>
std::string inputErrorOf(Action&& action) {
    try {
        action();
    } catch (const InputError& e) {
        return e.what();
    }
    ADD_FAILURE() << "expected an InputError";
    return {};
}

// Every one of `parts` is in `message`.
inline void expectContains(const std::string& message, std::initializer_list<std::string> parts) {
    for (const std::string& part : parts)
        EXPECT_NE(message.find(part), std::string::npos) << "'" << part << "' not in: " << message;
}

inline void expectContains(const std::string& message, const std::string& part) {
    expectContains(message, {part});
}

}  // namespace deltagi::test
