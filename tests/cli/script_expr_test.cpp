// The `{...}` arithmetic of scripts: grammar, precedence, functions and every error.

#include <cmath>

#include <gtest/gtest.h>

#include "clients/cli/script_expr.h"

namespace strata::cli {
namespace {

/// Evaluates `text` with n bound to `n` (and i to 10); the test fails on an error.
double eval(const std::string& text, double n = 3) {
    auto e = Expression::compile(text, {"n", "i"});
    EXPECT_TRUE(e.has_value()) << text << ": " << (e.has_value() ? "" : e.error().message);
    if (!e) return std::nan("");
    Bindings vars;
    vars.push("i", 10);
    vars.push("n", n);
    auto v = e.value().evaluate(vars);
    EXPECT_TRUE(v.has_value()) << text << ": " << (v.has_value() ? "" : v.error().message);
    return v.has_value() ? v.value() : std::nan("");
}

std::string compile_error(const std::string& text) {
    auto e = Expression::compile(text, {"n"});
    return e.has_value() ? "" : e.error().message;
}

std::string eval_error(const std::string& text, double n) {
    auto e = Expression::compile(text, {"n"});
    if (!e) return "compile: " + e.error().message;
    Bindings vars;
    vars.push("n", n);
    auto v = e.value().evaluate(vars);
    return v.has_value() ? "" : v.error().message;
}

TEST(ScriptExpr, FollowsTheUsualPrecedence) {
    EXPECT_DOUBLE_EQ(eval("1 + 2 * 3"), 7);
    EXPECT_DOUBLE_EQ(eval("(1 + 2) * 3"), 9);
    EXPECT_DOUBLE_EQ(eval("10 - 4 - 3"), 3);
    EXPECT_DOUBLE_EQ(eval("12 / 3 / 2"), 2);
    EXPECT_DOUBLE_EQ(eval("2 ^ 3 ^ 2"), 512);
    EXPECT_DOUBLE_EQ(eval("-2 ^ 2"), -4);
    EXPECT_DOUBLE_EQ(eval("2 ^ -1"), 0.5);
    EXPECT_DOUBLE_EQ(eval("--n"), 3);
    EXPECT_DOUBLE_EQ(eval("+n * 2"), 6);
    EXPECT_DOUBLE_EQ(eval(" n*0.5+1.25e1 "), 14);
}

TEST(ScriptExpr, ModuloTakesTheSignOfTheDivisor) {
    EXPECT_DOUBLE_EQ(eval("n % 2"), 1);
    EXPECT_DOUBLE_EQ(eval("(n - 4) % 10", 3), 9);
    EXPECT_DOUBLE_EQ(eval("7 % -3"), -2);
    EXPECT_DOUBLE_EQ(eval("5.5 % 2"), 1.5);
    EXPECT_DOUBLE_EQ(eval("n * 37 % 10000", 300), 1100);
}

TEST(ScriptExpr, HasTheDocumentedFunctionsAndConstants) {
    EXPECT_NEAR(eval("sin(pi / 2)"), 1, 1e-12);
    EXPECT_NEAR(eval("cos(pi)"), -1, 1e-12);
    EXPECT_NEAR(eval("atan2(1, 1)"), M_PI / 4, 1e-12);
    EXPECT_DOUBLE_EQ(eval("sqrt(16) + abs(-2)"), 6);
    EXPECT_DOUBLE_EQ(eval("floor(2.7) + ceil(2.1) + round(2.5)"), 8);
    EXPECT_DOUBLE_EQ(eval("min(n, 2) + max(n, 2)"), 5);
    EXPECT_DOUBLE_EQ(eval("pow(1.1, 2)"), std::pow(1.1, 2));
    EXPECT_DOUBLE_EQ(eval("clamp(n, 0, 2) + clamp(-n, 0, 2)"), 2);
    EXPECT_NEAR(eval("log(exp(2)) + e - e"), 2, 1e-12);
    EXPECT_NEAR(eval("tan(0) + asin(0) + acos(1) + atan(0)"), 0, 1e-12);
}

TEST(ScriptExpr, InnerBindingsHideOuterOnes) {
    auto e = Expression::compile("n * 100 + i", {"n", "i"});
    ASSERT_TRUE(e.has_value());
    Bindings vars;
    vars.push("n", 1);
    vars.push("i", 2);
    vars.push("n", 5);
    EXPECT_DOUBLE_EQ(e.value().evaluate(vars).value(), 502);
    EXPECT_EQ(vars.describe(), "n=1, i=2, n=5");
    vars.pop();
    EXPECT_DOUBLE_EQ(e.value().evaluate(vars).value(), 102);
}

TEST(ScriptExpr, RefusesBadTextWithItsColumn) {
    EXPECT_NE(compile_error("1 +").find("text ended"), std::string::npos);
    EXPECT_NE(compile_error("(1 + 2").find("expected ')'"), std::string::npos);
    EXPECT_NE(compile_error("1 2").find("unexpected '2' at column 3"), std::string::npos);
    EXPECT_NE(compile_error("n $ 2").find("unexpected '$'"), std::string::npos);
    EXPECT_NE(compile_error("").find("text ended"), std::string::npos);
    EXPECT_NE(compile_error("1..2").find("unexpected"), std::string::npos);
}

TEST(ScriptExpr, RefusesUnknownNamesAndFunctionsWhenCompiled) {
    EXPECT_NE(compile_error("m + 1").find("unknown name 'm'"), std::string::npos);
    EXPECT_NE(compile_error("m + 1").find("in scope: n"), std::string::npos);
    EXPECT_NE(compile_error("sine(n)").find("unknown function 'sine'"), std::string::npos);
    EXPECT_NE(compile_error("min(n)").find("min() takes 2 arguments, not 1"), std::string::npos);
    EXPECT_NE(compile_error("sin(n, 2)").find("takes 1 argument, not 2"), std::string::npos);
    auto outside = Expression::compile("n", {});
    ASSERT_FALSE(outside.has_value());
    EXPECT_NE(outside.error().message.find("no repeat encloses this step"), std::string::npos);
}

TEST(ScriptExpr, RefusesNestingDeepEnoughToHurt) {
    EXPECT_NE(compile_error(std::string(200, '(') + "1" + std::string(200, ')')).find("too deeply"),
              std::string::npos);
    EXPECT_NE(compile_error(std::string(200, '-') + "1").find("too deeply"), std::string::npos);
}

TEST(ScriptExpr, DivisionByZeroAndNonFiniteResultsAreErrorsNotNumbers) {
    EXPECT_NE(eval_error("1 / n", 0).find("division by zero (n=0)"), std::string::npos);
    EXPECT_NE(eval_error("1 % n", 0).find("modulo by zero"), std::string::npos);
    EXPECT_NE(eval_error("sqrt(n)", -1).find("not finite"), std::string::npos);
    EXPECT_NE(eval_error("10 ^ n", 400).find("not finite"), std::string::npos);
    EXPECT_EQ(eval_error("1 / n", 2), "");
}

TEST(ScriptExpr, VariableNamesExcludeConstantsAndFunctions) {
    EXPECT_TRUE(is_variable_name("n"));
    EXPECT_TRUE(is_variable_name("frame_2"));
    EXPECT_TRUE(is_variable_name("_i"));
    EXPECT_FALSE(is_variable_name(""));
    EXPECT_FALSE(is_variable_name("2n"));
    EXPECT_FALSE(is_variable_name("a-b"));
    EXPECT_FALSE(is_variable_name("pi"));
    EXPECT_FALSE(is_variable_name("sin"));
}

TEST(ScriptExpr, NumbersFormatWithoutNoise) {
    EXPECT_EQ(format_number(3), "3");
    EXPECT_EQ(format_number(-0.0), "0");
    EXPECT_EQ(format_number(-12), "-12");
    EXPECT_EQ(format_number(0.1), "0.1");
    EXPECT_EQ(format_number(0.1 + 0.2), "0.30000000000000004");
    EXPECT_EQ(format_number(1e20), "1e+20");
}

}  // namespace
}  // namespace strata::cli
