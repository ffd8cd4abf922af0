// The rest check at its full length: the light patient on the coarse array, released,
// settled by 1.6 s, then 10 s at rest: the bags and the bed board carry his weight within
// 0.5 % on average over the rest and the mechanical energy does not grow over it (the
// thresholds are the default test's, PatientAtRest.h). About 10-20 minutes.
#include "PatientAtRest.h"

TEST(PatientOnArrayLong, OverATenSecondRestTheBagsCarryHisWeightAndEnergyDoesNotGrow) {
    cosim::test::checkLightPatientSettlesAndRests(11.6, 10.0);
}
