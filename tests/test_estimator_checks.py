"""scikit-learn's estimator contract: every check of ``parametrize_with_checks`` on ``dgmm.GaussianMixture``."""
from sklearn.utils.estimator_checks import parametrize_with_checks

from dgmm import GaussianMixture


@parametrize_with_checks([GaussianMixture(n_components=2, random_state=0)])
def test_scikit_learn_estimator_checks(estimator, check):
    check(estimator)
