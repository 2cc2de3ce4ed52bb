from setuptools import setup

PACKAGE = "bearing_diagnoser"

setup(
    name=PACKAGE,
    version="0.1.0",
    packages=[PACKAGE, f"{PACKAGE}.decision", f"{PACKAGE}.spectral", f"{PACKAGE}.fold",
              f"{PACKAGE}.health", f"{PACKAGE}.reports"],
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + PACKAGE]),
        ("share/" + PACKAGE, ["package.xml"]),
    ],
    install_requires=["setuptools"],
    zip_safe=False,
    maintainer="bearing-monitor maintainers",
    maintainer_email="maintainers@bearing-monitor.invalid",
    description="Fault decision from observer residuals (thesis 3.2) with onset times and confidence; "
                "diagnoser node, bearing-diagnose and bearing-accuracy.",
    license="Apache-2.0",
    entry_points={
        "console_scripts": [
            'diagnoser = bearing_diagnoser.executables:diagnoser',
            'bearing-diagnose = bearing_diagnoser.diagnose_cli:main',
            'bearing-accuracy = bearing_diagnoser.accuracy_cli:main',
            'bearing-trend = bearing_diagnoser.health.trend_cli:main',
        ],
    },
)
