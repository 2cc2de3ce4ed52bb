from setuptools import setup

PACKAGE = "bearing_observer"

setup(
    name=PACKAGE,
    version="0.1.0",
    packages=[PACKAGE],
    package_data={'bearing_observer': ['models/*/*.json']},
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + PACKAGE]),
        ("share/" + PACKAGE, ["package.xml"]),
    ],
    install_requires=["setuptools"],
    zip_safe=False,
    maintainer="bearing-monitor maintainers",
    maintainer_email="maintainers@bearing-monitor.invalid",
    description=("Hammerstein-Wiener identification (thesis 2.4, app. B-C) and outer-/inner-race fault observers "
                 "(thesis 3.1, app. D-E); observer node and bearing-identify CLI."),
    license="Apache-2.0",
    entry_points={
        "console_scripts": [
            'observer = bearing_observer.executables:observer',
            'bearing-identify = bearing_observer.identify_cli:main',
        ],
    },
)
