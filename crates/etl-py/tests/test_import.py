import etlcal


def test_version_is_the_crate_version():
    assert etlcal.__version__ == "0.1.0"
