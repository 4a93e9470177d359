// knitsim command line (SPEC 2.10). Placeholder until the CLI lands.
#include <iostream>
int main() {
  std::cout << "knitsim\n";
  return 0;
}
