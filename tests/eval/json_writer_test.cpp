#include <limits>

#include <gtest/gtest.h>

#include "ssta/core/json_writer.h"
#include "ssta/core/error.h"

namespace ssta::internal {
namespace {

TEST(eval_JsonWriter, WritesNestedDocumentWithNullForNaN) {
  JsonWriter json;
  json.BeginObject();
  json.Key("name");
  json.String("a \"b\"\n");
  json.Key("values");
  json.BeginInlineArray();
  json.Integer(1);
  json.Number(0.25);
  json.Number(std::numeric_limits<double>::quiet_NaN());
  json.EndArray();
  json.Key("list");
  json.BeginArray();
  json.Bool(true);
  json.Null();
  json.EndArray();
  json.Key("empty");
  json.BeginObject();
  json.EndObject();
  json.EndObject();
  EXPECT_EQ(json.Take(),
            "{\n"
            "  \"name\": \"a \\\"b\\\"\\n\",\n"
            "  \"values\": [1, 0.25, null],\n"
            "  \"list\": [\n"
            "    true,\n"
            "    null\n"
            "  ],\n"
            "  \"empty\": {}\n"
            "}\n");
}

TEST(eval_JsonWriter, NumbersReadBackExactly) {
  JsonWriter json;
  json.Number(1.0 / 3.0);
  const std::string text = json.Take();
  EXPECT_EQ(std::stod(text), 1.0 / 3.0);
}

TEST(eval_JsonWriter, ValueWithoutKeyInObjectIsAProgrammerError) {
  JsonWriter json;
  json.BeginObject();
  EXPECT_THROW(json.Integer(1), InternalError);
}

}  // namespace
}  // namespace ssta::internal
