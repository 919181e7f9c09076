// make_fuzz_seeds DIR: writes fuzz/seeds.h's seeds as DIR/TARGET/NAME (scripts/fuzz.sh adds the
// small sample meshes of libcgal-demo and scenes/*.json).
#include <filesystem>
#include <fstream>
#include <iostream>

#include "fuzz/seeds.h"
#include "fuzz/targets.h"

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  if (argc != 2) {
    std::cerr << "usage: make_fuzz_seeds DIR\n";
    return 2;
  }
  const fs::path dir = argv[1];
  for (const std::string& t : ptc::fuzz::target_names()) fs::create_directories(dir / t);
  for (const ptc::fuzz::Seed& s : ptc::fuzz::generated_seeds())
    std::ofstream(dir / s.target / s.name, std::ios::binary) << s.bytes;
  std::cout << "seeds written to " << dir.string() << "\n";
  return 0;
}
