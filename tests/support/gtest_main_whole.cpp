// main() of the test executables that CTest runs whole (omnislam_add_gtest ... WHOLE): like
// gtest_main, but exits with 77, which CTest reports as "skipped", when no test passed and some
// were skipped (e.g. a dataset is absent); a partly skipped run exits as GoogleTest says.
#include <gtest/gtest.h>

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  const int rc = RUN_ALL_TESTS();
  const testing::UnitTest& u = *testing::UnitTest::GetInstance();
  if (rc == 0 && u.successful_test_count() == 0 && u.skipped_test_count() > 0) return 77;
  return rc;
}
