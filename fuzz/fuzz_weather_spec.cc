// Weather specs (generator/weather_spec.h), parsed strictly and resolved; the resolved spec must parse
// back (a resolved spec is what dataset.json records).
#include "core/json_reader.h"
#include "fuzz/fuzz_common.h"
#include "generator/weather_spec.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace weathergs;
  using namespace weathergs::generator;
  const std::string path = fuzz::write_input(data, size, "weather.json");
  return fuzz::expect_only_input_errors([&] {
    const WeatherSpec spec = parse_weather_spec(JsonReader::from_file(path));
    const WeatherSpec again = parse_weather_spec(JsonReader(spec.to_json(), "resolved"));
    if (again.to_json() != spec.to_json()) {
      std::fprintf(stderr, "resolved spec does not round-trip\n");
      std::abort();
    }
  });
}
