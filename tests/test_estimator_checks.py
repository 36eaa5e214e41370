"""scikit-learn's estimator contract: every check of ``parametrize_with_checks`` on ``dgmm.GaussianMixture``."""
from sklearn.utils.estimator_checks import parametrize_with_checks

from dgmm import GaussianMixture


@parametrize_with_checks([GaussianMixture(n_components=2, covariance_type=covariance_type, random_state=0)
                          for covariance_type in ("full", "tied", "diag", "spherical")])
def test_scikit_learn_estimator_checks(estimator, check):
    check(estimator)
